"""``teachbot study run`` at a real terminal (pexpect): instructions, a session, the questionnaire, a pause."""

import json
import os
import shlex
import sys
from pathlib import Path

import pexpect
import pytest

from dialog.transcripts.jsonl import read_session
from tests.e2e.teach_helpers import PRINTED, answer, next_question

pytestmark = pytest.mark.e2e
TEACHBOT = str(Path(sys.executable).with_name("teachbot"))

STUDY = """
name = "terminal"
seed = 5
ids = ["T01", "T02"]
order = "given"
folder = "records"
pause = "Take a short break now."
[orders]
T01 = ["ask", "quiet"]
T02 = ["quiet", "ask"]
[[conditions]]
name = "ask"
strategy = "active"
turns = 3
budget = 5
instructions = "Condition ASK: label what the robot points at."
[[conditions]]
name = "quiet"
strategy = "active"
turns = 3
budget = 1
instructions = "Condition QUIET: the robot may ask once."
[[questionnaire]]
id = "ease"
kind = "likert"
text = "Teaching was easy."
points = 5
anchors = ["disagree", "agree"]
[[questionnaire]]
id = "notes"
kind = "text"
text = "Anything else?"
"""


def spawn_study(cwd: Path, *args):
    env = dict(os.environ, TERM="dumb", NO_COLOR="1", COLUMNS="200")
    return pexpect.spawn(TEACHBOT, ["study", *args], cwd=str(cwd), env=env, encoding="utf-8", timeout=120,
                         dimensions=(50, 200), echo=True)


def test_a_participant_runs_a_session_and_a_questionnaire_at_the_terminal(tmp_path):
    (tmp_path / "study.toml").write_text(STUDY)
    child = spawn_study(tmp_path, "run", "study.toml", "--participant", "T01", "--no-viewer")
    child.expect_exact("=== Session 1 of 2 ===")
    child.expect_exact("Condition ASK: label what the robot points at.")
    child.expect_exact("Press Enter to begin.")
    child.sendline("")
    for number in range(3):
        assert next_question(child) == "label"
        if number == 0:
            answer(child, "purple elephant", "I didn't understand")
            child.expect("> ")
        answer(child, "a fruit", "is a fruit")
    child.expect_exact("Session over: 3 of 3 turns.")
    child.expect_exact("1 = disagree ... 5 = agree")
    child.expect("> ")
    answer(child, "9", "Please type a whole number from 1 to 5")
    child.expect("> ")
    answer(child, "4", "Anything else?")
    child.expect("> ")
    answer(child, "it pointed well", "Answers saved.")
    child.expect_exact("Take a short break now.")
    child.sendline("")
    child.expect_exact("=== Session 2 of 2 ===")
    child.expect_exact("Press Enter to begin.")
    child.sendline("")
    assert next_question(child) == "label"
    child.sendeof()  # the participant leaves mid-session: it is saved and resumes later
    child.expect_exact(f"Continue with: {PRINTED} study run study.toml --participant T01 --no-viewer")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0

    folder = tmp_path / "records" / "T01"
    header, records = read_session(folder / "1-ask.jsonl")
    assert header["study"]["participant"] == "T01" and header["study"]["condition"] == "ask"
    assert header["study"]["order"] == 1 and header["teacher"] == {"kind": "terminal"}
    assert [r["answer"]["parsed"] for r in records] == ["fruit"] * 3
    assert records[0]["answer"]["lines"] == ["purple elephant", "a fruit"]
    lines = [json.loads(line) for line in (folder / "1-ask-questionnaire.jsonl").read_text().splitlines()]
    assert lines[0]["questionnaire"]["condition"] == "ask"
    assert lines[1:] == [{"item": "ease", "kind": "likert", "value": 4},
                         {"item": "notes", "kind": "text", "value": "it pointed well"}]
    assert not (folder / "2-quiet-questionnaire.jsonl").exists()

    status = spawn_study(tmp_path, "status", "study.toml")
    status.expect(pexpect.EOF)
    assert "running 0/3" in status.before and "1 done" in status.before

    child = spawn_study(tmp_path, "run", "study.toml", "--participant", "T01", "--no-viewer")  # goes on
    child.expect_exact("1 to run now.")
    child.expect_exact("=== Session 2 of 2 ===")
    child.expect_exact("(This session was interrupted after 0 turns; it goes on from there.)")
    child.sendline("")
    assert next_question(child) == "label"
    answer(child, "a snack", "is a snack")
    child.expect_exact("1 = disagree ... 5 = agree")
    child.expect("> ")
    answer(child, "skip", "Anything else?")
    child.expect("> ")
    answer(child, "", "Answers saved.")
    child.expect_exact("T01: all sessions done for now.")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0
    records = read_session(folder / "2-quiet.jsonl")[1]
    assert len(records) == 3 and records[0]["answer"]["parsed"] == "snack"
    assert [r["action"]["kind"] for r in records[1:]] == ["none", "none"]  # budget 1: one question
    answers = [json.loads(line) for line in (folder / "2-quiet-questionnaire.jsonl").read_text().splitlines()[1:]]
    assert [a["value"] for a in answers] == [None, None]

    again = spawn_study(tmp_path, "run", "study.toml", "--participant", "T01")
    again.expect(pexpect.EOF)
    again.close()
    assert again.exitstatus == 2 and "already done every session" in again.before


def test_the_continue_line_repeats_the_folder_and_runs_as_printed(tmp_path):
    """Issue 23 case 5: the printed command dropped --folder, so it went to the default folder and said done."""
    (tmp_path / "study.toml").write_text(STUDY)
    child = spawn_study(tmp_path, "run", "study.toml", "--participant", "T02", "--folder", "pilot", "--no-viewer")
    child.expect_exact("Press Enter to begin.")
    child.sendline("")
    assert next_question(child) == "label"
    child.sendeof()
    child.expect(r"Continue with: ([^\r\n]+)")
    printed = child.match.group(1).strip()
    child.expect(pexpect.EOF)
    assert printed == f"{PRINTED} study run study.toml --participant T02 --folder pilot --no-viewer"
    words = shlex.split(printed)
    again = pexpect.spawn(TEACHBOT, words[1:], cwd=str(tmp_path), env=dict(os.environ, TERM="dumb", NO_COLOR="1"),
                          encoding="utf-8", timeout=120, dimensions=(50, 200))
    again.expect_exact("(This session was interrupted after 0 turns; it goes on from there.)")
    again.sendeof()
    again.expect(pexpect.EOF)
    assert (tmp_path / "pilot" / "T02" / "1-quiet.jsonl").exists() and not (tmp_path / "records").exists()


@pytest.mark.parametrize("pilot", [False, True])
def test_participants_see_no_condition_strategy_or_budget_unless_a_pilot_asks(tmp_path, pilot):
    """Issue 23, case 3: "Session 1 of 2" and the instructions only; --show-conditions brings the rest back."""
    import subprocess

    (tmp_path / "study.toml").write_text(STUDY)
    answers = ["", "fruit", "fruit", "fruit", "4", "fine", "", ""]
    run = subprocess.run([TEACHBOT, "study", "run", "study.toml", "--participant", "T02", "--no-viewer",
                          *(["--show-conditions"] if pilot else [])], cwd=tmp_path, input="\n".join(answers) + "\n",
                         capture_output=True, text=True, timeout=180, env=dict(os.environ, NO_COLOR="1"))
    assert run.returncode == 0, run.stderr
    shown = run.stdout
    assert "=== Session 1 of 2" in shown and "Condition QUIET: the robot may ask once." in shown
    revealing = ("(quiet)", "(ask)", "active", "budget", "quiet, ask", "quiet-questionnaire")
    if pilot:
        assert "=== Session 1 of 2 (quiet) ===" in shown and "budget left" in shown and "quiet, ask" in shown
    else:
        assert [word for word in revealing if word in shown] == []
        assert "Robot stays quiet." in shown  # the quiet turns, without the reason that names the budget


BLIND_STUDY = """
name = "blind"
seed = 11
ids = ["B01"]
order = "given"
folder = "records"
pause = "Take a short break now."
[orders]
B01 = ["cond-alpha", "cond-beta"]
[[conditions]]
name = "cond-alpha"
strategy = "active"
task = "sort-groceries"
turns = 2
budget = 5
instructions = "Teach the robot what it points at."
[[conditions]]
name = "cond-beta"
strategy = "all-cd"
task = "serve-salad"
turns = 2
budget = 5
instructions = "Teach the robot again."
[[questionnaire]]
id = "ease"
kind = "likert"
text = "Teaching was easy."
points = 5
anchors = ["disagree", "agree"]
"""
#: what names a condition: its name, its strategy, its task, and file names made of them (issue 42 case 3)
CONDITION_WORDS = (r"cond-alpha", r"cond-beta", r"\bactive\b", r"all-cd", r"sort-groceries", r"serve-salad",
                   r"1-cond", r"2-cond")


def test_nothing_a_participant_sees_at_the_terminal_names_a_condition(tmp_path):
    """``--no-viewer`` sessions show each question's picture path (``Picture: ...``): it used to be
    ``records/B01/1-cond-alpha-pictures/...``, naming the condition the browser study hides."""
    import io
    import re

    (tmp_path / "study.toml").write_text(BLIND_STUDY)
    seen = io.StringIO()
    child = spawn_study(tmp_path, "run", "study.toml", "--participant", "B01", "--no-viewer")
    child.logfile_read = seen
    child.expect_exact("Press Enter to begin.")
    child.sendline("")
    while child.expect(["What is the|Which features|Can you show", "1 = disagree"]) == 0:
        child.expect("> ")
        child.sendline("skip")  # every question of the session; then the questionnaire
    child.expect("> ")
    child.sendline("4")
    child.expect_exact("Take a short break now.")
    child.sendline("")
    child.expect_exact("=== Session 2 of 2 ===")
    child.expect_exact("Press Enter to begin.")
    child.sendeof()
    child.expect(pexpect.EOF)
    child.close()
    shown = seen.getvalue()
    assert "Picture: records/B01/1-pictures/scene-" in shown, shown  # the picture is still shown, by position
    named = [word for word in CONDITION_WORDS if re.search(word, shown)]
    assert not named, (named, shown)
    pictures = list((tmp_path / "records" / "B01" / "1-pictures").glob("*.png"))
    assert pictures and (tmp_path / "records" / "B01" / "1-cond-alpha.jsonl").is_file()
