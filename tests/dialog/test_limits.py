"""Issue 24: every size, count and time has a stated maximum (learning/data/limits.toml), refused in one line
before any work starts; command-line numbers are ASCII digits; a value starting with '-' is told what is wrong."""

from __future__ import annotations

import signal
import time

import pytest

from dialog.cli import main
from dialog.experiments.suite import SuiteError, load_suite
from dialog.settings import EpisodeSettings
from dialog.study.studyfile import load_study
from learning.errors import DataFileError, SettingsError
from learning.limits import maximum

SUITE = """
name = "tiny"
strategies = ["passive"]
datasets = 2
checkpoints = [1, 2, 4]
[[condition]]
name = "static"
budget = 3
turns = 4
change_every = 2
"""

STUDY = """
name = "tiny"
seed = 1
participants = 1
[[conditions]]
name = "a"
strategy = "active"
turns = 3
[[questionnaire]]
id = "ease"
kind = "likert"
text = "Easy?"
anchors = ["no", "yes"]
"""


class StillRunning(Exception):
    """A command that should have been refused at once was still running: a hang, not a refusal."""


def _hang(signum, frame):
    raise StillRunning("still running after 60 s instead of a refusal")


def _one_line(capsys, *argv) -> str:
    """The single stderr line of a refused command (exit 2, no traceback), and it came at once."""
    start = time.monotonic()
    previous = signal.signal(signal.SIGALRM, _hang)
    signal.alarm(60)
    try:
        code = main(list(argv))
    except SystemExit as exit_:
        code = exit_.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    captured = capsys.readouterr()
    assert code == 2, captured
    assert time.monotonic() - start < 30, "refused only after work had started"
    assert "Traceback" not in captured.err and "usage:" not in captured.err
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    return lines[0]


@pytest.mark.parametrize("argv, expected", [
    (["demo", "--turns", "100000000"], "turns: 100000000 is beyond the limit of 10000 turns in one episode"),
    (["demo", "--embodied-costs", "--time", "1e9s"], "--time: 1e+09 is beyond the limit of 20000 seconds"),
    (["demo", "--embodied-costs", "--time", "100000000"], "turns: 100000000 is beyond the limit"),
    (["demo", "--budget", "1e300"], "budget: 1e+300 is beyond the limit of 1e+06 cost units"),
    (["teach", "--realtime", "1e300"], "realtime: 1e+300 is beyond the limit of 3600 seconds per turn"),
    (["regress", "--suite", "smoke", "--datasets", "1000000"], "--datasets: 1000000 is beyond the limit of 100"),
    (["demo", "--turns", "10000", "--budget", "1e6"], "can pay for 10000 questions, beyond the limit of 2000"),
    (["train-questioner", "--out", "q.toml", "--steps", "1000000000"], "steps: 1000000000 is beyond the limit"),
    (["train-questioner", "--out", "q.toml", "--envs", "1000"], "envs: 1000 is beyond the limit of 32 worker"),
    (["regress", "--suite", "smoke", "--workers", "100000"], "--workers: 100000 is beyond the limit of 32 worker"),
])
def test_a_run_beyond_a_limit_is_refused_before_it_starts(capsys, argv, expected, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    line = _one_line(capsys, *argv)
    assert expected in line and "learning/data/limits.toml" in line, line


@pytest.mark.parametrize("argv, expected", [
    (["demo", "--seed", "٣"], "--seed: '٣' is not a whole number"),
    (["regress", "--suite", "smoke", "--seeds", "1_0"], "--seeds: '1_0' is not a whole number"),
    (["demo", "--turns", "٣"], "--turns: expected a whole number, got '٣'"),
    (["demo", "--budget", "١.٥"], "--budget: expected a number of cost units, got '١.٥'"),
    (["demo", "--time", "٣"], "--time: '٣' is not a number of turns"),
])
def test_numbers_are_ascii_digits_only(capsys, argv, expected):
    line = _one_line(capsys, *argv)
    assert expected in line, line


def test_a_seed_given_twice_is_refused(capsys):
    assert "--seeds: seed 0 is given twice; give each seed once" in _one_line(
        capsys, "regress", "--suite", "smoke", "--seeds", "0", "0")


@pytest.mark.parametrize("argv, expected", [
    (["demo", "--time", "-5s"], "--time: '-5s' is not a number of turns (e.g. --time 40) or of seconds ending in s"),
    (["demo", "--budget", "-inf"], "--budget: expected a number of cost units, got '-inf', which is not a finite"),
    (["demo", "--budget", "-5"], "--budget: the budget can't be negative, got -5"),
    (["demo", "--task", "-x"], "--task: no task '-x'; accepted: "),
    (["demo", "--transcript", "-x.jsonl"], "--transcript: '-x.jsonl' starts with '-' and reads as an option; write "
                                           "--transcript=-x.jsonl"),
])
def test_a_value_that_starts_with_a_dash_is_told_what_is_wrong(capsys, argv, expected):
    line = _one_line(capsys, *argv)
    assert expected in line and "needs a value" not in line, line


def test_an_output_path_under_proc_is_named_as_such(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    line = _one_line(capsys, "demo", "--turns", "1", "--transcript", "/proc/x.jsonl")
    assert "a file system of the kernel's" in line and "no space left" not in line, line


def _suite(tmp_path, old: str, new: str):
    assert old in SUITE
    path = tmp_path / "tiny.toml"
    path.write_text(SUITE.replace(old, new))
    return load_suite(path)


@pytest.mark.parametrize("old, new, expected", [
    ("datasets = 2", "datasets = 1000000", "'datasets' must be >= 1 and <= 100, got 1000000"),
    ("turns = 4", "turns = 100000000", "'turns' must be >= 1 and <= 10000, got 100000000"),
    ("budget = 3", "budget = 1e300", "'budget' must be >= 0 and <= 1e+06"),
    ("turns = 4", "turns = 4\nseconds = 1e300", "'seconds' must be > 0 and <= 20000"),
    ("checkpoints = [1, 2, 4]", "checkpoints = [16, 4, 4]", "'checkpoints' must be in increasing order"),
    ("checkpoints = [1, 2, 4]", "checkpoints = [1, 2, 5]", "checkpoint 5 lies beyond every condition"),
    ("datasets = 2", "datasets = 2\nseeds = [0, 0]", "seeds: seed 0 is given twice"),
    ("datasets = 2", f"datasets = 2\nseeds = {list(range(1001))}", "1001 seeds are beyond the limit of 1000"),
])
def test_a_suite_beyond_a_limit_or_out_of_order_is_refused(tmp_path, old, new, expected):
    with pytest.raises(SuiteError, match=None) as raised:
        _suite(tmp_path, old, new)
    assert expected in str(raised.value) and str(tmp_path / "tiny.toml") in str(raised.value)


def test_the_shipped_suites_are_within_the_limits():
    from dialog.experiments.suite import suite_names

    for name in suite_names():
        load_suite(name)


def test_a_study_with_realtime_beyond_the_clock_is_refused(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(STUDY.replace("turns = 3", "turns = 3\nrealtime = 1e300"))
    with pytest.raises(DataFileError, match=r"'realtime' must be > 0 and <= 3600, got 1e\+300"):
        load_study(path)


@pytest.mark.parametrize("field, value", [("turns", 10_001), ("budget", 1e7), ("realtime", 1e300),
                                          ("seconds", 1e9)])
def test_episode_settings_beyond_a_limit_are_refused(field, value):
    with pytest.raises(SettingsError, match="is beyond the limit"):
        EpisodeSettings(**{field: value})
    assert maximum(field) < value


def test_a_task_with_too_many_concepts_is_refused(tmp_path):
    from bullet_world.catalogue import load_task

    names = [f"c{i}" for i in range(maximum("concepts") + 1)]
    path = tmp_path / "big.toml"
    path.write_text(f'name = "big"\nconcepts = {names}\nobjects = "x"\nobjects_per_scene = 70\ntest_scenes = 1\n')
    with pytest.raises(DataFileError, match="33 concepts are beyond the limit of 32"):
        load_task(path)


def test_no_command_line_number_is_read_by_plain_int_or_float():
    """Every number option goes through the ASCII-digit types of dialog/commands/_arguments.py."""
    import argparse

    from tests.dialog.test_cli_arguments import ALL_PARSERS

    for path, parser in ALL_PARSERS:
        for action in parser._actions:
            if not isinstance(action, argparse._SubParsersAction):
                assert action.type not in (int, float), f"{' '.join(path)} {action.option_strings}: type={action.type}"
