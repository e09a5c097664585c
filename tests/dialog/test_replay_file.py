"""A replay teacher's file (``teach --teacher replay --replay F``) passes the checks every transcript read does.

Issue 42 case 4: a link to /dev/zero was read until MemoryError (18 s, 6 GB) and a FIFO hung; a record whose
answer was not a table was a traceback. Each is now one line naming the file, before anything is read.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from dialog.episode import make_teacher
from dialog.transcripts import jsonl
from learning.errors import TranscriptError

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))


def _teach_replay(folder: Path, replay: str) -> subprocess.CompletedProcess:
    """Run in a child with a timeout and 2 GB of address space: a reader that hangs or reads forever fails."""
    command = [TEACHBOT, "teach", "--teacher", "replay", "--replay", replay, "--turns", "2", "--no-pictures",
               "--transcript", "out.jsonl"]
    return subprocess.run(["/bin/sh", "-c", 'ulimit -v 2000000; exec "$@"', "sh", *command], cwd=folder,
                          capture_output=True, text=True, timeout=90, stdin=subprocess.DEVNULL)


@pytest.mark.parametrize("kind", ["a link to /dev/zero", "a FIFO"])
def test_a_device_or_a_fifo_as_the_replay_file_is_refused_in_one_line_without_reading(tmp_path, kind):
    if kind == "a FIFO":
        os.mkfifo(tmp_path / "replay.jsonl")
    else:
        os.symlink("/dev/zero", tmp_path / "replay.jsonl")
    result = _teach_replay(tmp_path, "replay.jsonl")
    assert result.returncode == 2, result.stderr[-2000:]
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    shown = "a character device" if "zero" in kind else "a FIFO (named pipe)"
    assert f"replay.jsonl: it is {shown}, not a regular file" in lines[0]
    assert not (tmp_path / "out.jsonl").exists() or (tmp_path / "out.jsonl").stat().st_size == 0


def test_a_transcript_larger_than_any_session_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.jsonl"
    with open(path, "wb") as handle:
        handle.truncate(jsonl.MAX_TRANSCRIPT_BYTES + 1)  # sparse: no disk used
    with pytest.raises(TranscriptError, match=r"big.jsonl: 163,840,001 bytes is more than a transcript holds"):
        make_teacher("replay", transcript=path)


@pytest.mark.parametrize("record, message", [
    ({"turn": 1, "answer": ["a fruit"]}, "line 1: 'answer' is [\"a fruit\"] (expected a table"),
    ({"turn": 1, "answer": None}, "line 1: 'answer' is null"),
    ({"turn": "one", "answer": {}}, "line 1: 'turn' is \"one\" (expected a whole number from 1"),
    ({"turn": 1, "answer": {"lines": "a fruit"}}, "line 1: 'answer.lines' is \"a fruit\""),
    ({"turn": 1, "answer": {"lines": ["\ud800"]}}, "'answer.lines' is [\"\\ud800\"] (expected a list of the lines"),
])
def test_a_replay_record_without_readable_lines_is_refused_naming_its_line(tmp_path, record, message):
    path = tmp_path / "replay.jsonl"
    path.write_text(json.dumps(record) + "\n")
    with pytest.raises(TranscriptError) as error:
        make_teacher("replay", transcript=path)
    assert str(error.value).startswith(f"{path}: ") and message in str(error.value)


def test_a_turn_answered_twice_in_a_replay_file_is_refused(tmp_path):
    path = tmp_path / "replay.jsonl"
    path.write_text('{"turn": 1, "answer": {"lines": ["a fruit"]}}\n' * 2)
    with pytest.raises(TranscriptError, match="line 2: 'turn' is 1 .expected a whole number from 1, once per turn"):
        make_teacher("replay", transcript=path)
