"""The terminal side of ``scripts/fuzz_teach.py``: one ``teachbot teach`` process in a pseudo-terminal.

It reads the screen the way a person does (the intro's concepts, each "Turn n
of T" question, the robot's reply to a typed line), types bytes with a
deadline, and reads transcripts back for the checks.
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import signal
import sys
import time
from io import StringIO
from pathlib import Path

import pexpect
from _fuzz_corpus import Question

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
QUESTION = re.compile(r"Turn (\d+) of \d+ · budget left[^\n]*\n(?:[^\n]*\n)*?Robot: ([^\r\n]*)\r?\n> ")
INTRO = re.compile(r"Teaching '[^']*' \(([^)]*)\) in ")
DEMO_RANGE = re.compile(r"\(1 to (\d+)\)")
SESSION_END = re.compile(r"Session saved after|Accuracy on ")
ROBOT = r"(?:^|\n|> )Robot: "  # a reply starts a line, or follows the "> " the answer was typed after
RESPONSES = {  # what the session does with one line; the earliest match in the output wins
    "ack": re.compile(ROBOT + r"(Thanks: |All right, there is no |There's none here, so I fetched|"
                      r"All right, let's move on\.|I'll skip this question\.|Too late)"),
    "undo": re.compile(ROBOT + "Taken back: "),
    "askback": re.compile(ROBOT + r"[^\n]*Did you mean"),
    "end": SESSION_END,
    "prompt": re.compile(r"\n> "),
}
VOLATILE = ("time", "ended")  # wall-clock fields of a turn record; the answer's "seconds" too


class Hang(Exception):
    """The session produced no expected output in time."""


def read_records(path: Path) -> list[dict]:
    """The turn records on disk (a last line cut short by a kill is left out)."""
    if not path.exists():
        return []
    records = []
    for line in path.read_bytes().decode("utf-8", errors="replace").splitlines():
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            continue
        if isinstance(record, dict) and "turn" in record:
            records.append(record)
    return records


def comparable(records: list[dict]) -> list[dict]:
    """Turn records without their wall-clock fields."""
    kept = []
    for record in records:
        record = {key: value for key, value in record.items() if key not in VOLATILE}
        if isinstance(record.get("answer"), dict):
            record["answer"] = {key: value for key, value in record["answer"].items() if key != "seconds"}
        kept.append(record)
    return kept


class Process:
    """One ``teachbot teach`` process in a pseudo-terminal."""

    def __init__(self, args: list[str], timeout: float, command: str = TEACHBOT):
        env = dict(os.environ, TERM="dumb", NO_COLOR="1", COLUMNS="200", PYTHONUNBUFFERED="1")
        self.log = StringIO()
        self.timeout = timeout
        self.child = pexpect.spawn(command, ["teach", *args], env=env, encoding="utf-8", codec_errors="replace",
                                   timeout=timeout, dimensions=(50, 200), echo=False, maxread=65536)
        self.child.logfile_read = self.log
        flags = fcntl.fcntl(self.child.child_fd, fcntl.F_GETFL)
        fcntl.fcntl(self.child.child_fd, fcntl.F_SETFL, flags | os.O_NONBLOCK)
        self.concepts: tuple[str, ...] = ()
        self.acked: list[int] = []       # turns the robot acknowledged
        self.confirmed = 0               # how many of them were followed by further output (a question, the end)

    def expect(self, patterns: list) -> int:
        index = self.child.expect([*patterns, pexpect.EOF, pexpect.TIMEOUT])
        if index == len(patterns) + 1:
            raise Hang()
        return index  # len(patterns): end of output

    def write(self, data: bytes) -> None:
        """Type ``data``; a terminal that takes no input for ``timeout`` seconds is a hang."""
        deadline = time.monotonic() + self.timeout
        sent = 0
        while sent < len(data):
            try:
                sent += os.write(self.child.child_fd, data[sent:sent + 4096])
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise Hang() from None
                time.sleep(0.005)
            except OSError:  # the process is gone; what it printed tells why
                return

    def next_question(self) -> Question | None:
        """Wait for the next question; None once the session ended."""
        index = self.expect([INTRO, QUESTION, SESSION_END])
        if index == 0:
            self.concepts = tuple(c.strip() for c in self.child.match.group(1).split(","))
            index = self.expect([QUESTION, SESSION_END]) + 1
        self.confirmed = len(self.acked)
        if index != 1:
            return None
        turn, text = int(self.child.match.group(1)), self.child.match.group(2)
        if text.startswith("What is"):
            return Question(turn, "label", concepts=self.concepts)
        if text.startswith("Can you show me"):
            match = DEMO_RANGE.search(text)
            return Question(turn, "demo", n_objects=int(match.group(1)) if match else 1, concepts=self.concepts)
        return Question(turn, "feature", concepts=self.concepts)

    def respond(self) -> str:
        """How the session took the last line: "ack", "undo", "askback", "end", "prompt" or "eof"."""
        names = list(RESPONSES)
        index = self.expect(list(RESPONSES.values()))
        return names[index] if index < len(names) else "eof"

    def finish(self) -> int | None:
        """Wait for the process to end; its exit status (None if it died of a signal)."""
        try:
            self.child.expect(pexpect.EOF, timeout=self.timeout)
        except pexpect.TIMEOUT:
            self.child.kill(signal.SIGKILL)
            raise Hang() from None
        self.child.close()
        return self.child.exitstatus

    def kill(self) -> None:
        self.child.kill(signal.SIGKILL)
        self.child.close(force=True)

    def tracebacks(self) -> str | None:
        text = self.log.getvalue()
        at = text.find("Traceback (most recent call last)")
        return None if at < 0 else text[at:][-600:]


def process_state(pid: int) -> str:
    """The state letter of a process (R, S, T, Z, ...); "" when it is gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return ""


def first_difference(reference: list[dict], resumed: list[dict]) -> str:
    if len(reference) != len(resumed):
        return f"{len(reference)} turns uninterrupted, {len(resumed)} after the resume"
    for a, b in zip(comparable(reference), comparable(resumed)):
        for key in sorted(set(a) | set(b)):
            if a.get(key) != b.get(key):
                return f"turn {a.get('turn')} field {key}: {str(a.get(key))[:80]} vs {str(b.get(key))[:80]}"
    return "a session did not finish"
