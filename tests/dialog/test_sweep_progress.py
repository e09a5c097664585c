"""Issue 43 item 3: one progress line for a whole run (every data seed, every suite of make experiments)."""

import io
import re

from dialog.cli import main
from dialog.experiments.progress import EVENT, LOG_EVERY, SweepProgress, clock_time, progress_line, relay
from tests.dialog.test_regress import write_suite

PROGRESS = re.compile(r"^episodes \d+/\d+")


class FakeClock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_the_line_gives_done_of_total_the_rate_and_the_time_left():
    assert progress_line(0, 120, 0.0) == "episodes 0/120 (0%), 0:00 elapsed"
    assert progress_line(40, 120, 16.0) == "episodes 40/120 (33%), 0:16 elapsed, 2.50/s, ETA 0:32"
    assert progress_line(3, 4, 3600.0, doing="data seed 1") == \
        "episodes 3/4 (75%), 1:00:00 elapsed, 0.00/s, ETA 20:00 · data seed 1"
    assert clock_time(3725) == "1:02:05" and clock_time(59.6) == "1:00" and clock_time(-1) == "0:00"


def test_off_a_terminal_a_line_comes_at_most_every_log_interval_and_once_at_the_end():
    clock, stream = FakeClock(), io.StringIO()
    line = SweepProgress(1000, stream=stream, clock=clock, interactive=False)
    for _ in range(1000):  # 1000 episodes over 100 seconds
        clock.now += 0.1
        line.advance()
    line.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == int(100 / LOG_EVERY) + 1
    assert all(PROGRESS.match(text) for text in lines) and "\r" not in stream.getvalue()
    assert lines[-1] == "episodes 1000/1000 (100%), 1:40 elapsed, 10.00/s, ETA 0:00"


def test_a_short_run_off_a_terminal_writes_only_its_last_line():
    clock, stream = FakeClock(), io.StringIO()
    line = SweepProgress(5, stream=stream, clock=clock, interactive=False)
    for _ in range(5):
        clock.now += 1.0
        line.advance()
    line.close()
    assert stream.getvalue() == "episodes 5/5 (100%), 0:05 elapsed, 1.00/s, ETA 0:00\n"


def test_on_a_terminal_the_line_is_redrawn_in_place_and_notes_go_above_it():
    clock, stream, out = FakeClock(), io.StringIO(), io.StringIO()
    line = SweepProgress(2, stream=stream, clock=clock, interactive=True)
    clock.now += 1.0
    line.advance()
    line.note("data seed 0 done", out)
    clock.now += 1.0
    line.advance()
    line.close()
    assert out.getvalue() == "data seed 0 done\n"
    text = stream.getvalue()
    assert text.count("\n") == 1 and text.endswith("episodes 2/2 (100%), 0:02 elapsed, 1.00/s, ETA 0:00\n")
    assert "\r" + " " * len("episodes 1/2 (50%), 0:01 elapsed, 1.00/s, ETA 0:01") + "\r" in text  # cleared


def test_a_parent_advances_its_line_on_a_child_s_events_and_shows_its_other_messages():
    clock, stream, out = FakeClock(), io.StringIO(), io.StringIO()
    line = SweepProgress(3, stream=stream, clock=clock, interactive=False)
    relay([f"{EVENT}\n", "teachbot regress: a warning\n", f"{EVENT}\n", f"{EVENT}\n"], line, out)
    assert line.done == 3 and out.getvalue() == "teachbot regress: a warning\n"


def progress_lines(err: str) -> list[str]:
    return [text for text in err.replace("\r", "\n").splitlines() if PROGRESS.match(text)]


def test_regress_on_two_data_seeds_shows_one_line_for_all_their_episodes(tmp_path, capsys):
    suite, out = write_suite(tmp_path), tmp_path / "out"
    assert main(["regress", "--suite", str(suite), "--data-seeds", "0", "1", "--results", str(out),
                 "--workers", "1"]) == 0
    captured = capsys.readouterr()
    lines = progress_lines(captured.err)
    assert lines and all("/8 " in line for line in lines), captured.err  # one count over both: not 4 twice
    assert lines[-1].startswith("episodes 8/8 (100%)") and "\r" not in captured.err
    elapsed = [int(minutes) * 60 + int(seconds) for minutes, seconds in re.findall(r"(\d+):(\d\d) elapsed",
                                                                                   lines[-1])]
    assert len(lines) <= elapsed[0] // LOG_EVERY + 1  # not a flood: a line per LOG_EVERY seconds at most
    assert "data seed 1:" in captured.out
    assert main(["regress", "--suite", str(suite), "--data-seeds", "0", "1", "--results", str(out),
                 "--workers", "1", "--no-progress"]) == 0
    assert progress_lines(capsys.readouterr().err) == []


def test_regress_for_a_parent_reports_each_episode_as_an_event(tmp_path, capsys):
    suite, out = write_suite(tmp_path), tmp_path / "out"
    assert main(["regress", "--suite", str(suite), "--results", str(out), "--workers", "1",
                 "--progress-events"]) == 0
    err = capsys.readouterr().err
    assert err.splitlines().count(EVENT) == 4 and progress_lines(err) == []
