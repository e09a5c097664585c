"""One writer per transcript: two real processes on one file, one refuses with a line naming the file and holder."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from dialog.transcripts.jsonl import TranscriptWriter, read_session
from dialog.transcripts.lock import TranscriptLock
from learning.errors import TranscriptError

pytestmark = pytest.mark.e2e
TEACHBOT = str(Path(sys.executable).with_name("teachbot"))


def race(tmp_path, *commands: list[str]) -> list[tuple[subprocess.Popen, str, str]]:
    """Start every command at once; wait for all; each process with its stdout and stderr."""
    processes = [subprocess.Popen([TEACHBOT, *command], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                  text=True) for command in commands]
    return [(process, *process.communicate(timeout=300)) for process in processes]


def check_one_refused(outcomes, path: Path, command: str) -> subprocess.Popen:
    """Exactly one process ran (exit 0); the other exited 2 with one line naming the file and the winner's pid."""
    codes = sorted(process.returncode for process, _, _ in outcomes)
    assert codes == [0, 2], [(p.returncode, err[-2000:]) for p, _, err in outcomes]
    (winner, _, _), = [o for o in outcomes if o[0].returncode == 0]
    (_, _, err), = [o for o in outcomes if o[0].returncode == 2]
    assert "Traceback" not in err
    lines = [line for line in err.strip().splitlines() if not line.startswith("pybullet build time")]
    assert len(lines) == 1, err
    assert re.fullmatch(rf"teachbot {command}: {re.escape(str(path))} is in use by another teachbot process "
                        rf"\(pid {winner.pid}: teachbot {command} .*\); wait until it ends or choose another "
                        r"--transcript", lines[0]), lines[0]
    return winner


def test_two_teach_processes_on_one_transcript_one_refuses_and_the_file_stays_resumable(tmp_path):
    path = tmp_path / "D.jsonl"
    outcomes = race(tmp_path, *(["teach", "--teacher", "scripted", "--turns", "12", "--seed", str(seed),
                                 "--transcript", str(path), "--json"] for seed in (1, 2)))
    winner = check_one_refused(outcomes, path, "teach")
    summary = json.loads(next(o for o in outcomes if o[0] is winner)[1].strip().splitlines()[-1])
    header, records = read_session(path)  # strict: every line is JSON
    assert header["seed"] == summary["seed"] and [r["turn"] for r in records] == list(range(1, 13))
    resumed = subprocess.run([TEACHBOT, "teach", "--resume", str(path)], cwd=tmp_path, capture_output=True,
                             text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert read_session(path) == (header, records)  # a finished session resumes to the same file


def test_two_demo_processes_on_one_transcript_lose_no_turn(tmp_path):
    path = tmp_path / "D.jsonl"
    outcomes = race(tmp_path, *(["demo", "--turns", "20", "--seed", str(seed), "--transcript", str(path)]
                                for seed in (1, 2)))
    check_one_refused(outcomes, path, "demo")
    header, records = read_session(path)
    assert [r["turn"] for r in records] == list(range(1, 21))


def test_a_lock_left_by_a_killed_process_does_not_block(tmp_path):
    path = tmp_path / "t.jsonl"
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from dialog.transcripts.lock import "
                               "TranscriptLock; lock = TranscriptLock(sys.argv[1]); print('held', flush=True); "
                               "time.sleep(120)", str(path)], stdout=subprocess.PIPE, text=True,
                              cwd=Path(__file__).resolve().parents[2])
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(TranscriptError, match=rf"is in use by another teachbot process \(pid {holder.pid}"):
            TranscriptWriter(path)
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=30)
    deadline = time.monotonic() + 10
    while True:  # the kernel frees the lock as the process dies: nothing stale to remove
        try:
            with TranscriptWriter(path) as writer:
                writer.write({"turn": 1})
            break
        except TranscriptError:
            assert time.monotonic() < deadline
            time.sleep(0.1)
    assert read_session(path)[1] == [{"turn": 1}]


def test_a_closed_writer_frees_its_transcript_for_the_next(tmp_path):
    path = tmp_path / "t.jsonl"
    with TranscriptWriter(path) as writer:
        writer.write({"turn": 1})
        with pytest.raises(TranscriptError, match="in use by another teachbot process"):
            TranscriptLock(path)
    with TranscriptWriter(path, append=True) as writer:
        writer.write({"turn": 2})
    assert [r["turn"] for r in read_session(path)[1]] == [1, 2]
