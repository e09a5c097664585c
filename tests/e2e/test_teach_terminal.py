"""``teachbot teach`` driven through a pseudo-terminal: every kind of answer a person gives."""

import pexpect
import pytest

from dialog.transcripts.jsonl import read_session
from tests.e2e.teach_helpers import PRINTED, answer, next_question, spawn

pytestmark = pytest.mark.e2e


def test_a_person_teaches_at_the_terminal(tmp_path):
    path = tmp_path / "session.jsonl"
    child = spawn("--strategy", "all-cd", "--turns", "14", "--budget", "30", "--change-every", "6", "--seed", "1",
                  "--transcript", path, cwd=tmp_path)
    child.expect_exact("Type 'help' at any question")

    assert next_question(child) == "feature"  # all-cd asks which features matter first
    answer(child, "why", "Why I ask:")
    child.expect("> ")
    answer(child, "1.1, 1.2", "Thanks: I'll use")

    assert next_question(child) == "demo"
    answer(child, "blah blah", "I didn't understand 'blah blah'")
    child.expect("> ")
    answer(child, "number 3", "Thanks: number 3 is")

    assert next_question(child) == "demo"
    answer(child, "undo", "Taken back: number 3 is")
    child.expect("> ")
    answer(child, "4", "Thanks: number 4 is")

    kinds = []
    while (kind := next_question(child)) == "demo":
        answer(child, str(len(kinds) + 5), "Thanks: number")
        kinds.append(kind)
    assert kind == "label"
    answer(child, "frut", "(I take 'frut' as 'fruit'.)")
    assert next_question(child) == "label"
    answer(child, "Snacks!", "is a snack.")
    assert next_question(child) == "label"
    child.sendeof()
    child.expect_exact("Session saved after")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0

    header, records = read_session(path)
    assert header["strategy"] == "all-cd" and header["teacher"] == {"kind": "terminal"}
    assert len(records) == 1 + 2 + len(kinds) + 2  # features, two demonstrations, the rest, two labels
    feature = records[0]
    assert feature["action"] == {"kind": "feature"} and feature["answer"]["lines"] == ["why", "1.1, 1.2"]
    assert feature["answer"]["parsed"][:3] == ["colour.red", "colour.green", "colour.blue"]
    assert feature["model"]["features_in_use"] == len(feature["answer"]["parsed"])
    assert records[1]["answer"]["lines"] == ["blah blah", "number 3"] and records[1]["answer"]["parsed"] == 3
    assert records[2]["undid"] == [2] and records[2]["answer"]["parsed"] == 4
    assert sum(records[2]["model"]["examples"].values()) == 1  # the first demonstration was taken back
    first_label, second_label = records[-2], records[-1]
    assert first_label["answer"]["raw"] == "frut" and first_label["answer"]["parsed"] == "fruit"
    assert second_label["answer"]["parsed"] == "snack"
    assert first_label["gesture"]["reached"] and first_label["picture"].endswith(".png")
    assert (tmp_path / first_label["picture"]).exists()
    fields = {"turn", "time", "action", "question", "answer", "cost", "budget_left", "scene_id", "model"}
    assert all(fields <= set(record) for record in records)


def test_the_continue_line_repeats_unrecorded_options_and_runs_as_printed(tmp_path):
    """Issue 23 case 5: every "continue with" line repeats the options its transcript does not record."""
    import shlex

    child = spawn("--turns", "3", "--transcript", "my session.jsonl", "--pictures", "pics", cwd=tmp_path)
    next_question(child)
    child.sendeof()
    child.expect(r"Continue it with: ([^\r\n]+)")
    printed = child.match.group(1).strip()
    child.expect(pexpect.EOF)
    assert printed == f"{PRINTED} teach --resume 'my session.jsonl' --pictures pics"
    again = spawn(*shlex.split(printed)[2:], cwd=tmp_path)
    again.expect_exact("Transcript: my session.jsonl")
    next_question(again)
    again.sendeof()
    again.expect(pexpect.EOF)
    assert (tmp_path / "pics").is_dir() and (tmp_path / "my session.jsonl").exists()
