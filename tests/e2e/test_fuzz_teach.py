"""``scripts/fuzz_teach.py``: hostile lines, Ctrl-C/D/Z and kill -9 against real ``teachbot teach`` sessions."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"
sys.path.insert(0, str(SCRIPTS))
from _fuzz_corpus import LITERAL_NEXT, Question, hostile_line, out_of_range_numbers, typed, valid_answer  # noqa: E402
from _fuzz_terminal import comparable, first_difference, read_records  # noqa: E402

KEYS = ("inputs", "sessions", "tracebacks", "hangs", "lost_turns", "guessed", "kills", "resumes_identical")
LABEL = Question(3, "label", concepts=("main dish", "snack", "fruit", "beverage"))
DEMO = Question(4, "demo", n_objects=12, concepts=LABEL.concepts)


def test_control_bytes_are_typed_literally_and_every_line_ends_with_enter():
    assert typed(b"ab") == b"ab\n"
    assert typed(b"\x00\x03\x1b[3~\x7f") == (LITERAL_NEXT + b"\x00" + LITERAL_NEXT + b"\x03" + LITERAL_NEXT
                                              + b"\x1b[3~" + LITERAL_NEXT + b"\x7f\n")
    assert typed("\u00e9\U0001f34e".encode()) == "\u00e9\U0001f34e\n".encode()  # UTF-8 passes untouched


def test_out_of_range_numbers_name_nothing_the_question_offers():
    rng = np.random.default_rng(0)
    for question, top in ((LABEL, 4), (DEMO, 12)):
        for text in out_of_range_numbers(question, rng):
            assert not (text.isdigit() and 1 <= int(text) <= top), text


def test_the_corpus_is_seeded_and_never_holds_a_valid_answer():
    first = [hostile_line(DEMO, np.random.default_rng(5)) for _ in range(3)]
    again = [hostile_line(DEMO, np.random.default_rng(5)) for _ in range(3)]
    assert first == again
    rng = np.random.default_rng(1)
    lines = set()
    for question in (LABEL, DEMO):
        hostile = {hostile_line(question, rng)[1] for _ in range(400)}
        assert not hostile & {valid_answer(question, rng).encode() for _ in range(50)}
        lines |= hostile
    assert any(len(line) > 300 for line in lines) and any(b"\x00" in line for line in lines)
    assert any(line.decode("utf-8", errors="replace") != line.decode("utf-8", errors="ignore") for line in lines)


def test_resumed_transcripts_compare_without_their_clock_fields(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text('{"session": {}}\n{"turn": 1, "time": 1.5, "ended": 2.0, "answer": {"raw": "3", "seconds": 0.4}}'
                    '\n{"turn": 2, "answ')  # the last line was cut short by a kill
    records = read_records(path)
    assert [r["turn"] for r in records] == [1]
    later = [{"turn": 1, "time": 9.0, "ended": 9.9, "answer": {"raw": "3", "seconds": 7.0}}]
    assert comparable(records) == comparable(later)
    other = [{"turn": 1, "time": 1.5, "ended": 2.0, "answer": {"raw": "4", "seconds": 0.4}}]
    assert comparable(records) != comparable(other)
    assert "field answer" in first_difference(records, other)


@pytest.mark.e2e
def test_a_small_fuzz_run_reports_a_clean_session_log(tmp_path):
    run = subprocess.run([sys.executable, str(SCRIPTS / "fuzz_teach.py"), "--inputs", "40", "--kills", "2",
                          "--turns", "8", "--budget", "12", "--exit-chance", "1", "--ctrl-z", "0.1", "--seed", "3",
                          "--keep", str(tmp_path), "--json"], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    assert set(KEYS) <= set(summary)
    assert summary["inputs"] >= 40 and summary["kills"] == 2 and summary["sessions"] >= 3
    assert summary["tracebacks"] == 0 and summary["hangs"] == 0 and summary["lost_turns"] == 0, summary["examples"]
    assert summary["guessed"] == 0, summary["examples"]
    assert summary["resumes_identical"] == 2, summary["examples"]
    assert summary["resumes"] >= 2 + 1  # every kill and at least one Ctrl-C/Ctrl-D exit was resumed
    controls = summary["controls"]
    assert controls["ctrl_c"] == controls["ctrl_c_exit_130"] and controls["ctrl_d"] == controls["ctrl_d_saved"]
    assert controls["ctrl_z"] == controls["ctrl_z_stopped"] + controls["sigstop"]  # stopped, then continued
    assert len(run.stderr.strip().splitlines()) >= summary["sessions"]  # a progress line per session
    transcripts = sorted(tmp_path.glob("*.jsonl"))
    assert len(transcripts) == 2 * 2 + summary["sessions"] - 2  # a reference and a killed run per kill
    assert all(len(read_records(path)) == 8 for path in transcripts)  # every session reached its last turn
