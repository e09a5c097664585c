"""Kill ``teachbot teach`` with SIGKILL mid-session, resume it: no answered turn is lost, the models go on."""

import signal

import pytest

from dialog.transcript import read_session
from tests.e2e.teach_helpers import answer, next_question, spawn

pytestmark = pytest.mark.e2e
ANSWERS = {"label": "a fruit", "demo": "2", "feature": "1"}


def test_sigkill_then_resume_loses_no_answered_turn(tmp_path):
    path = tmp_path / "session.jsonl"
    child = spawn("--strategy", "active", "--turns", "8", "--budget", "10", "--change-every", "3", "--seed", "4",
                  "--transcript", path, cwd=tmp_path)
    for _ in range(4):
        kind = next_question(child)
        answer(child, ANSWERS[kind], "Thanks:")
    assert next_question(child) == "label"  # the fifth question is open when the process dies
    child.kill(signal.SIGKILL)
    child.close(force=True)
    assert child.signalstatus == signal.SIGKILL

    before = path.read_bytes()
    header, records = read_session(path, tolerate_partial_tail=True)
    assert [r["turn"] for r in records] == [1, 2, 3, 4]
    assert records[-1]["model"]["examples"]["fruit"] == 4

    resumed = spawn("--resume", path, cwd=tmp_path)
    resumed.expect_exact("(resuming after turn 4)")
    answered = 0
    while (kind := next_question(resumed)) != "end":
        answer(resumed, ANSWERS[kind], "Thanks:")
        answered += 1
    resumed.close()
    assert resumed.exitstatus == 0 and answered == 4

    after = path.read_bytes()
    assert after.startswith(before)  # the answered turns are kept byte for byte
    header_again, records = read_session(path)
    assert header_again == header and [r["turn"] for r in records] == list(range(1, 9))
    assert records[4]["model"]["examples"]["fruit"] == 5  # the replayed answers are in the model
    assert records[-1]["model"]["examples"]["fruit"] == 8
    assert records[4]["time"] >= records[3]["ended"]  # the session clock goes on from where it stopped
