"""The terminal teacher: injected streams, no TTY needed, deadlines without sleeping; and a fuzz test."""

import io
import os

import numpy as np
import pytest

from dialog.clock import VirtualClock
from dialog.language.feature_tree import FeatureTree
from dialog.language.parsing import AnswerParser
from dialog.language.questions import Prompt
from dialog.teachers.conversation import converse
from dialog.teachers.terminal import TIMEOUT, LineReader, TerminalTeacher
from learning.actions import DemoQuery, FeatureQuery, LabelQuery
from tests.dialog.fakes import CONCEPTS, FakeEnvironment

TREE = FeatureTree(("f1", "f2", "f3"), [("object/colour", "Redness"), ("object/size", "Length"), ("robot", "Joint")])


@pytest.fixture(scope="module")
def scene():
    return FakeEnvironment(objects=12).next_scene(np.random.default_rng(0))


def prompt(scene, action, deadline=None):
    return Prompt(3, 10, 7.0, action, "What is the red round thing, number 4? I'm pointing at it.",
                  "I can't tell fruit from snack.", scene, CONCEPTS, details=["Picture: runs/p.png", "no. colour"],
                  feature_tree=TREE if action.kind == "feature" else None, deadline=deadline)


def test_a_session_without_a_tty(scene):
    out = io.StringIO()
    teacher = TerminalTeacher(io.StringIO("frut\nwhy\nfruit\n"), out, clock=VirtualClock())
    outcome = converse(teacher, prompt(scene, LabelQuery(3)), AnswerParser(CONCEPTS), VirtualClock())
    assert (outcome.kind, outcome.value, outcome.lines) == ("answer", "fruit", ["frut"])
    text = out.getvalue()
    assert "Turn 3 of 10 · budget left 7" in text and "Picture: runs/p.png" in text
    assert "Robot: What is the red round thing, number 4?" in text and "> frut" in text
    assert "\x1b[" not in text  # plain text when the output is not a terminal


def make_pipe(data: bytes):
    read_fd, write_fd = os.pipe()
    os.write(write_fd, data)
    return os.fdopen(read_fd, "rb", buffering=0), write_fd


def test_line_reader_on_a_pipe_with_timeouts_and_bad_bytes():
    stream, write_fd = make_pipe(b"one\r\ntw\xffo\nthr")
    reader = LineReader(stream)
    assert reader.readline(timeout=0) == "one"
    assert reader.readline(timeout=0) == "tw\ufffdo"
    assert reader.readline(timeout=0) is TIMEOUT  # "thr" has no newline yet and nothing more is coming in time
    os.write(write_fd, b"ee\nlate 1\nlate 2\n")
    assert reader.readline(timeout=0) == "three"
    assert reader.drain() == 2
    os.close(write_fd)
    assert reader.readline(timeout=0) is None
    stream.close()


def test_a_deadline_passes_without_waiting_and_stale_lines_are_dropped(scene):
    stream, write_fd = make_pipe(b"")
    out = io.StringIO()
    clock = VirtualClock(20.0)
    teacher = TerminalTeacher(stream, out, clock=clock)
    outcome = converse(teacher, prompt(scene, LabelQuery(0), deadline=20.0), AnswerParser(CONCEPTS), clock)
    assert outcome.kind == "late"
    os.write(write_fd, b"a fruit\n")
    teacher.show(prompt(scene, LabelQuery(1)))
    assert "ignored 1 line(s) typed after the time ran out" in out.getvalue()
    os.close(write_fd)
    stream.close()


def test_real_time_mode_counts_down_at_the_prompt(scene, monkeypatch):
    """Issue 23 case 11: real-time mode said how long there was only once, above the question."""
    import re

    import dialog.teachers.terminal
    monkeypatch.setattr(dialog.teachers.terminal, "COUNTDOWN_MARKS", (1.4, 0.6))
    stream, write_fd = make_pipe(b"")
    out = io.StringIO()
    clock = VirtualClock(0.0)
    teacher = TerminalTeacher(stream, out, clock=clock)
    converse(teacher, prompt(scene, LabelQuery(0), deadline=2.0), AnswerParser(CONCEPTS), clock)  # waits 2 s
    assert re.findall(r"\[(\d+) s left\] > ", out.getvalue()) == ["2", "1", "1"]
    os.close(write_fd)
    stream.close()


def hostile_inputs(count: int, seed: int = 0) -> list[bytes]:
    """Random and hostile answer lines (no newline inside): unicode, control bytes, empty, huge, tricky."""
    rng = np.random.default_rng(seed)
    fixed = [b"", b" ", b"\t\t", b"\x00", b"\x1b[31mred\x1b[0m", b"\xff\xfe\xfd", b"9" * 5000, b"-1", b"0",
             b"1e309", b"nan", b"#", b"%s %n {0} {}", b"'; DROP TABLE answers; --", b"\xe2\x80\xae fruit",
             "fru\u0301\u0301\u0301it".encode(), "\U0001f34e".encode(), b"number " + b"9" * 400, b"1.1-1.999",
             b"ignore", b"all but", b"no", b"none none none", b"undo undo", b"\r", b"a" * (1 << 20),
             ("\u00e9" * 300000).encode(), b"\x07" * 1000, b"fruit\x00snack"]
    inputs = list(fixed)
    alphabet = [chr(c) for c in (*range(32, 127), 0x0301, 0x200B, 0x202E, 0xFEFF, 0x00A0, 0x3000, 0x6C34, 0x1F600)]
    words = ["fruit", "snack", "main", "dish", "none", "why", "undo", "skip", "quit", "help", "number", "4", "1.2",
             "ignore", "not", "a", "the", "don't", "know", "frut", "beverages", "yes", "no", "all"]
    while len(inputs) < count:
        kind = rng.integers(5)
        if kind == 0:
            text = "".join(rng.choice(alphabet, size=int(rng.integers(0, 40))))
            inputs.append(text.encode("utf-8"))
        elif kind == 1:
            inputs.append(bytes(int(b) for b in rng.integers(0, 256, size=int(rng.integers(0, 30))) if b != 10))
        elif kind == 2:
            inputs.append(" ".join(rng.choice(words, size=int(rng.integers(1, 6)))).encode())
        elif kind == 3:
            inputs.append(str(int(rng.integers(-100, 10**6))).encode())
        else:
            inputs.append(bytes(int(b) for b in rng.integers(0, 32, size=int(rng.integers(1, 10))) if b != 10))
    return inputs[:count]


READ_KINDS = {"answer", "absent", "choose", "reject", "unreadable", "help", "why", "undo", "skip", "quit",
              "dont_know"}


def test_fuzz_the_parser_with_a_thousand_hostile_inputs(scene):
    parser = AnswerParser(CONCEPTS)
    inputs = hostile_inputs(1000)
    assert len(inputs) >= 1000 and max(map(len, inputs)) >= 1 << 20
    for raw in inputs:
        text = raw.decode("utf-8", errors="replace")
        for reading in (parser.label(text), parser.demonstration(text, 12, "fruit"), TREE.read(text),
                        parser.choice(text, ("fruit", "snack"))):
            assert reading.kind in READ_KINDS
            if reading.kind == "unreadable":
                assert reading.message and "\n" not in reading.message and len(reading.message) < 600
            if reading.kind == "answer" and isinstance(reading.value, int):
                assert 0 <= reading.value < 12


def test_fuzz_the_terminal_teacher_every_line_is_read_or_asked_again(scene, tmp_path):
    inputs = hostile_inputs(1000, seed=1)
    path = tmp_path / "input.bin"
    path.write_bytes(b"\n".join(inputs) + b"\n")
    out = io.StringIO()
    told = []
    with open(path, "rb", buffering=0) as stream:
        teacher = TerminalTeacher(stream, out, clock=VirtualClock())
        original_tell = teacher.tell
        teacher.tell = lambda text: (told.append(text), original_tell(text))
        parser = AnswerParser(CONCEPTS)
        actions = [LabelQuery(3), DemoQuery("fruit"), FeatureQuery()]
        consumed, ended, questions = 0, 0, 0
        while True:
            outcome = converse(teacher, prompt(scene, actions[questions % 3]), parser, VirtualClock())
            questions += 1
            consumed += len(outcome.lines)
            if outcome.kind == "quit" and outcome.note == "end of input":
                break
            ended += 1
    assert consumed == len(inputs)
    asked_again = [text for text in told if not text.startswith("(")]  # "(I take 'frut' as 'fruit'.)" ends one
    assert consumed == ended + len(asked_again)  # each line ended its question or got an answer back
    assert all(len(line) <= 1000 for line in outcome.lines)
