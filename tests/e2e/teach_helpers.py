"""Drive ``teachbot teach`` through a pseudo-terminal (pexpect), as a person would."""

import os
import shlex
import sys
from pathlib import Path

import pexpect

from dialog.printed_command import program

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
PRINTED = shlex.join(program(TEACHBOT))  # how TEACHBOT, started by its full path, names itself in printed commands
QUESTIONS = {"feature": "Which features tell", "demo": "Can you show me", "label": "What is the"}


def spawn(*args, cwd=None, timeout=90):
    env = dict(os.environ, TERM="dumb", NO_COLOR="1", COLUMNS="200")
    return pexpect.spawn(TEACHBOT, ["teach", *map(str, args)], cwd=str(cwd) if cwd else None, env=env,
                         encoding="utf-8", timeout=timeout, dimensions=(50, 200), echo=True)


def next_question(child) -> str:
    """Wait for the next question and its prompt; returns its kind (or "end" when the session ended)."""
    index = child.expect([QUESTIONS["feature"], QUESTIONS["demo"], QUESTIONS["label"], pexpect.EOF])
    kind = ("feature", "demo", "label", "end")[index]
    if kind != "end":
        child.expect("> ")
    return kind


def answer(child, line: str, expect: str | None = None) -> None:
    child.sendline(line)
    if expect is not None:
        child.expect_exact(expect)
