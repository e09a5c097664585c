"""Kill ``teachbot teach`` with SIGKILL mid-session, resume it: no answered turn is lost, the models go on."""

import json
import signal

import pytest

from dialog.transcripts.jsonl import read_session
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


def scripted_session(path, *extra):
    from dialog.cli import main

    return main(["teach", "--teacher", "scripted", "--strategy", "active", "--turns", "5", "--budget", "10",
                 "--change-every", "2", "--seed", "6", "--transcript", str(path), "--no-pictures", *map(str, extra)])


def test_a_cut_scripted_session_resumes_to_the_same_bytes_and_old_transcripts_still_resume(tmp_path, capsys):
    from dialog.cli import main

    whole = tmp_path / "whole.jsonl"
    assert scripted_session(whole) == 0
    lines = whole.read_text().splitlines(keepends=True)
    assert all("scene_check" in json.loads(line) for line in lines[1:])

    cut = tmp_path / "cut.jsonl"
    cut.write_text("".join(lines[:3]))
    assert main(["teach", "--resume", str(cut), "--no-pictures"]) == 0
    assert cut.read_bytes() == whole.read_bytes()

    def old_format(line: str) -> str:  # a transcript written before records had a scene fingerprint
        record = json.loads(line)
        record.pop("scene_check", None)
        return json.dumps(record, ensure_ascii=False) + "\n"

    old = tmp_path / "old.jsonl"
    old.write_text("".join(old_format(line) for line in lines[:3]))
    capsys.readouterr()
    assert main(["teach", "--resume", str(old), "--no-pictures", "--json"]) == 0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["completed"] == 5

    header = json.loads(lines[0])
    header["session"]["seed"] = 7
    other_seed = tmp_path / "other-seed.jsonl"
    other_seed.write_text(json.dumps(header) + "\n" + "".join(old_format(line) for line in lines[1:3]))
    assert main(["teach", "--resume", str(other_seed), "--no-pictures"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"teachbot teach: {other_seed}: line 2: turn 1: the recorded question ")
    assert "made with another seed, task or kitchen" in err and "Traceback" not in err
