"""The feature question at a 50-line terminal (pexpect): the groups fit, a group opens, nothing is reprinted."""

import pexpect
import pytest

from dialog.transcripts.jsonl import read_session
from tests.e2e.teach_helpers import TEACHBOT, answer

pytestmark = pytest.mark.e2e

ROWS, COLUMNS = 50, 160


def spawn(*args, cwd):
    env = {"TERM": "dumb", "NO_COLOR": "1", "COLUMNS": str(COLUMNS), "LINES": str(ROWS), "PATH": "/usr/bin:/bin"}
    return pexpect.spawn(TEACHBOT, ["teach", *map(str, args)], cwd=str(cwd), env=env, encoding="utf-8", timeout=120,
                         dimensions=(ROWS, COLUMNS), echo=True)


def screen_lines(text: str) -> int:
    """Terminal rows ``text`` takes at COLUMNS wide."""
    return sum(max(1, -(-len(line.rstrip("\r")) // COLUMNS)) for line in text.split("\n"))


def test_the_feature_question_fits_fifty_lines_and_a_group_opens(tmp_path):
    path = tmp_path / "session.jsonl"
    child = spawn("--strategy", "all-cd", "--turns", "3", "--budget", "10", "--seed", "1", "--no-pictures",
                  "--transcript", path, cwd=tmp_path)
    child.expect_exact("Turn 1 of 3")
    child.expect_exact("> ")
    question = child.before
    assert "Which features tell" in question and "1 object: 51 features" in question
    assert "1.1.1.1" not in question  # the features wait until a group is opened
    assert screen_lines(question) + 1 <= ROWS, question

    answer(child, "more 3", "3 robot, 30 features")
    child.expect_exact("> ")
    assert "3.2.1.1 arm.joint1:" in child.before and screen_lines(child.before) <= ROWS
    answer(child, "appearance", "1.1 appearance, 11 features")
    child.expect_exact("> ")
    answer(child, "undo", "nothing left to take back")
    child.expect_exact("> ")
    assert "1 object: 51 features" not in child.before  # asked again, not reprinted
    answer(child, "zzz", "I don't know 'zzz'")
    child.expect_exact("> ")
    assert "1 object: 51 features" not in child.before
    answer(child, "1.1, 1.2", "Thanks: I'll use 24 of 86 features")
    child.sendline("quit")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0

    records = read_session(path)[1]
    feature = records[0]
    assert feature["action"] == {"kind": "feature"}
    assert feature["answer"]["lines"] == ["more 3", "appearance", "undo", "zzz", "1.1, 1.2"]
    assert feature["model"]["features_in_use"] == 24
