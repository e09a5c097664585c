"""Recorded study answers are never written over, and every study record read is checked (issue 24, items 1-3).

One simulated participant (P01 of the shipped example, about 4 s) is recorded once; each test damages a copy of
the records the way a crash, a slip of the hand or an edit would, and checks that ``study run`` neither asks
again what is recorded nor writes over it, that ``study status`` marks the session damaged (the study's status is
still shown) and that ``study report`` leaves it out and lists it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import os
import shutil
from pathlib import Path

import pytest

from dialog.cli import main
from dialog.study import questionnaire
from dialog.study.run import ParticipantRun
from dialog.study.studyfile import load_study

EXAMPLE = Path(__file__).resolve().parents[3] / "dialog" / "data" / "studies" / "example.toml"
SESSION = "P01/1-dt-task.jsonl"
ANSWERS = "P01/1-dt-task-questionnaire.jsonl"
NOTE = "P01/1-dt-task-aborted.json"


def study_cli(folder, *args):
    return main(["study", args[0], str(EXAMPLE), "--folder", str(folder), *args[1:]])


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    folder = tmp_path_factory.mktemp("recorded") / "d"
    assert study_cli(folder, "run", "--participant", "P01", "--simulated") == 0
    return folder


@pytest.fixture
def copy(recorded, tmp_path):
    target = tmp_path / "d"
    shutil.copytree(recorded, target)
    return target


def checksums(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "not a file"
            for p in sorted(folder.rglob("*")) if not p.is_dir() and "report" not in p.parts}


def one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in text, text
    return lines[0]


# -- case 1: a damaged transcript under recorded answers ----------------------------------------------------
@pytest.mark.parametrize("cut, shown", [("inside the last line", "ends after turn 7 of 8, and line 9 is torn"),
                                        ("after turn 3, line 5 torn", "ends after turn 3 of 8, and line 5 is torn"),
                                        ("after turn 3", "ends after turn 3 of 8, but the questionnaire")])
def test_a_transcript_cut_under_recorded_answers_is_damaged_and_never_continued(copy, capsys, cut, shown):
    """Issue 42 case 2: the questionnaire is asked only once the last turn is on disk, so a transcript that
    lost turns beside it was damaged afterwards; continuing it would record new turns under the old ratings."""
    lines = (copy / SESSION).read_bytes().splitlines(keepends=True)
    kept = {"inside the last line": b"".join(lines)[:-40], "after turn 3, line 5 torn": b"".join(lines[:4]) +
            lines[4][:30], "after turn 3": b"".join(lines[:4])}[cut]
    (copy / SESSION).write_bytes(kept)
    before = checksums(copy)
    assert study_cli(copy, "status") == 0
    out = capsys.readouterr().out
    assert "dt-task: running" not in out and "0 running" in out and "1 damaged" in out
    damaged = [line for line in out.splitlines() if line.startswith("damaged: P01 session 1 (dt-task): ")]
    assert len(damaged) == 1 and shown in damaged[0], out
    assert "restore the transcript, or run the condition again with --condition dt-task --again" in damaged[0]
    for extra in ([], ["--condition", "dt-task"]):
        assert study_cli(copy, "run", "--participant", "P01", "--simulated", *extra) == 2
        error = one_line(capsys.readouterr().err)
        assert "is damaged, so nothing was written" in error and shown in error
    assert checksums(copy) == before


def test_a_torn_transcript_without_answers_yet_resumes_from_its_last_whole_turn(copy, capsys):
    (copy / ANSWERS).unlink()
    lines = (copy / SESSION).read_bytes().splitlines(keepends=True)
    (copy / SESSION).write_bytes(b"".join(lines[:4]) + lines[4][:30])  # a crash while turn 4 was written
    assert study_cli(copy, "status") == 0
    assert "dt-task: running 3/8" in capsys.readouterr().out
    assert study_cli(copy, "run", "--participant", "P01", "--simulated") == 0
    now = (copy / SESSION).read_bytes().splitlines(keepends=True)
    assert now[:4] == lines[:4] and len(now) == 9  # the torn line dropped, the whole turns kept, the rest played
    assert (copy / ANSWERS).is_file()


@pytest.mark.parametrize("damage", ["delete", "empty"])
def test_a_transcript_deleted_or_emptied_under_recorded_answers_is_damaged_and_nothing_is_written(copy, capsys,
                                                                                                 damage):
    if damage == "delete":
        (copy / SESSION).unlink()
    else:
        (copy / SESSION).write_bytes(b"")
    before = checksums(copy)
    assert study_cli(copy, "run", "--participant", "P01", "--simulated") == 2
    error = one_line(capsys.readouterr().err)
    gone = "missing" if damage == "delete" else "empty"
    assert f"1-dt-task.jsonl: the transcript is {gone}, but the questionnaire after it is recorded" in error
    assert "--condition dt-task --again" in error
    assert checksums(copy) == before
    assert study_cli(copy, "status") == 0
    assert "damaged: P01 session 1 (dt-task)" in capsys.readouterr().out
    assert checksums(copy) == before
    # --again keeps every record, renamed, and runs the session afresh
    assert study_cli(copy, "run", "--participant", "P01", "--simulated", "--condition", "dt-task", "--again") == 0
    kept = copy / (ANSWERS + ".superseded-1")
    assert hashlib.sha256(kept.read_bytes()).hexdigest() == before[ANSWERS]


def test_saving_answers_never_replaces_recorded_ones(copy):
    path = copy / ANSWERS
    recorded = path.read_bytes()
    with pytest.raises(Exception, match="already holds the questionnaire answers; teachbot never writes over"):
        questionnaire.save(path, {"study": "example"}, [{"item": "ease", "kind": "likert", "value": 1}])
    assert path.read_bytes() == recorded
    assert not list(copy.rglob(".*.tmp"))


# -- case 4 and 5: damaged records are named, and mark only their session damaged -------------------------------
def _lines(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines(keepends=True)


def _edit_json_line(path: Path, index: int, change) -> None:
    lines = _lines(path)
    record = json.loads(lines[index])
    change(record)
    lines[index] = json.dumps(record) + "\n"
    path.write_text("".join(lines), encoding="utf-8")


def _note(folder: Path, **fields) -> None:
    note = {"study": "example", "participant": "P01", "condition": "dt-task", "order": 1, "software": "teachbot 0.1.0",
            "simulated": True,
            "reason": "felt unwell", "after_turns": 3} | fields
    (folder / NOTE).write_text(json.dumps({"aborted": note}) + "\n")


def _set(path, index, key, value, table=None):
    def change(record):
        (record[table] if table else record)[key] = value
    return lambda folder: _edit_json_line(folder / path, index, change)


def _set_study(path, table, key, value):
    def change(record):
        (record[table]["study"] if table == "session" else record[table])[key] = value
    return lambda folder: _edit_json_line(folder / path, 0, change)


def _drop(path, index, key):
    return lambda folder: _edit_json_line(folder / path, index, lambda record: record.pop(key))


def _write_line(path, index, text):
    def write(folder):
        lines = _lines(folder / path)
        lines[index] = text
        (folder / path).write_text("".join(lines))
    return write


def _duplicate(path, index):
    def write(folder):
        lines = _lines(folder / path)
        (folder / path).write_text("".join(lines + [lines[index]]))
    return write


def _extra_turn(folder):
    lines = _lines(folder / SESSION)
    record = json.loads(lines[-1]) | {"turn": 9}
    (folder / SESSION).write_text("".join(lines) + json.dumps(record) + "\n")


def _fifo(path: Path) -> None:
    path.unlink(missing_ok=True)
    os.mkfifo(path)  # reading it would block: it must be refused unopened


DAMAGES = {
    "note after_turns 'abc'": (lambda f: _note(f, after_turns="abc"), "'after_turns' is \"abc\" (expected a whole"),
    "note after_turns a list": (lambda f: _note(f, after_turns=[1]), "'after_turns' is [1]"),
    "note 0xFF bytes": (lambda f: (f / NOTE).write_bytes(b'{"aborted": {"reason": "\xff"}}\n'), "not UTF-8 text"),
    "note a list": (lambda f: (f / NOTE).write_text("[1, 2, 3]\n"), "not an abort note"),
    "note of another participant": (lambda f: _note(f, participant="P02"), "study participant is \"P02\""),
    "answer 'seven'": (_set(ANSWERS, 1, "value", "seven"), "item 'ease' has value \"seven\" (expected a whole number "
                                                          "from 1 to 7"),
    "Likert 99 on a 7-point item": (_set(ANSWERS, 1, "value", 99), "item 'ease' has value 99 (expected a whole number "
                                                                  "from 1 to 7"),
    "Likert true": (_set(ANSWERS, 1, "value", True), "item 'ease' has value true"),
    "answer without item": (_drop(ANSWERS, 1, "item"), "is not an answer (expected"),
    "answer [1,2,3]": (_write_line(ANSWERS, 2, "[1,2,3]\n"), "line 3: [1, 2, 3] is not an answer"),
    "duplicated answer": (_duplicate(ANSWERS, 1), "item 'ease' is answered twice (first on line 2"),
    "questionnaire of another participant": (_set(ANSWERS, 0, "participant", "P02", "questionnaire"),
                                             "the header's study participant is \"P02\""),
    "questionnaire of another condition": (_set(ANSWERS, 0, "condition", "active", "questionnaire"),
                                           "the header's study condition is \"active\""),
    "questionnaire not JSON": (_write_line(ANSWERS, 1, "{\"item\": \n"), "line 2: not a JSON record"),
    "turn without action": (_drop(SESSION, 3, "action"), "line 4: 'action' is null"),
    "turn 'three'": (_set(SESSION, 3, "turn", "three"), "line 4: 'turn' is \"three\""),
    "duplicated turn": (_duplicate(SESSION, 8), "line 10: 'turn' is 8 (expected turn 9"),
    "extra turn": (_extra_turn, "line 10: 'turn' is 9 (expected at most 8"),
    "accuracy 7": (_set(SESSION, 2, "accuracy", 7), "line 3: 'accuracy' is 7 (expected a held-out accuracy"),
    "header strategy edited": (_set(SESSION, 0, "strategy", "active", "session"),
                               "the session header's 'strategy' is \"active\" (expected \"dt-task\""),
    "header seed edited": (_set(SESSION, 0, "seed", 1, "session"), "the session header's 'seed' is 1 (expected"),
    "header turns edited": (_set(SESSION, 0, "turns", 9, "session"), "the session header's 'turns' is 9 (expected 8"),
    "transcript 0xFF bytes": (lambda f: (f / SESSION).write_bytes((f / SESSION).read_bytes().replace(
        b'"question": "', b'"question": "\xff', 1)), "line 2: not UTF-8 text"),
    "transcript a FIFO": (lambda f: _fifo(f / SESSION), "1-dt-task.jsonl: not a regular file (expected the "
                                                        "transcript"),
    "questionnaire a FIFO": (lambda f: _fifo(f / ANSWERS), "not a regular file (expected the questionnaire answers"),
    "note a FIFO": (lambda f: _fifo(f / NOTE), "not a regular file (expected the abort note"),
    "transcript nested 100000 deep": (_write_line(SESSION, 2, "[" * 100000 + "\n"), "line 3 nests JSON too deeply"),
    # issue 42: every field of the header, and every field of a turn, is what study run writes
    "turn without its answer": (_drop(SESSION, 3, "answer"), "line 4: the turn record has no 'answer' (expected"),
    "turn without its accuracy": (_drop(SESSION, 5, "accuracy"), "line 6: the turn record has no 'accuracy'"),
    "header software edited": (_set_study(SESSION, "session", "software", "hacked 9"),
                               "the header's study software is \"hacked 9\" (expected"),
    "header software a number": (_set_study(SESSION, "session", "software", 5), "study software is 5"),
    "header simulated 'yes'": (_set_study(SESSION, "session", "simulated", "yes"), "study simulated is \"yes\""),
    "header study table extra field": (_set_study(SESSION, "session", "name", "Ann"), "has a field \"name\" that"),
    "header teacher of a person": (_set(SESSION, 0, "teacher", {"kind": "terminal"}, "session"),
                                   "the session header's 'teacher' is {\"kind\": \"terminal\"} (expected"),
    "header costs edited": (_set(SESSION, 0, "costs", {"label": 0, "demo": 0, "feature": 0, "none": 0}, "session"),
                            "the session header's 'costs' is"),
    "header fetch_from_pantry edited": (_set(SESSION, 0, "fetch_from_pantry", False, "session"),
                                        "the session header's 'fetch_from_pantry' is false (expected true"),
    "header concepts edited": (_set(SESSION, 0, "concepts", ["fruit"], "session"), "the session header's 'concepts'"),
    "header unknown field": (_set(SESSION, 0, "zz_note", 1, "session"), "has a field \"zz_note\" that study run"),
    "questionnaire software edited": (_set_study(ANSWERS, "questionnaire", "software", ""), "study software is \"\""),
    "text answer a lone surrogate": (_set(ANSWERS, 3, "value", "\ud800zz"), "item 'comments' has a value that is "
                                                                           "not text (character 1 is U+D800"),
}


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_a_damaged_record_marks_its_session_damaged_names_the_line_and_loses_nothing(copy, capsys, damage):
    apply, message = DAMAGES[damage]
    apply(copy)
    before = checksums(copy)
    assert study_cli(copy, "status") == 0
    shown = capsys.readouterr().out
    damaged = [line for line in shown.splitlines() if line.startswith("damaged: ")]
    assert len(damaged) == 1 and damaged[0].startswith("damaged: P01 session 1 (dt-task): "), shown
    assert message in damaged[0], shown
    assert "1 damaged" in shown and "2 done" in shown  # the other sessions are read as before
    assert study_cli(copy, "report") == 0
    report = (copy / "report" / "report.md").read_text()
    assert "| P01 | 1 | dt-task | damaged |" in report
    capsys.readouterr()
    assert study_cli(copy, "run", "--participant", "P01", "--simulated", "--condition", "dt-task") == 2
    error = one_line(capsys.readouterr().err)
    assert "is damaged, so nothing was written" in error and message in error
    assert checksums(copy) == before


# -- item 3: names are not paths ---------------------------------------------------------------------------------
@pytest.mark.parametrize("participant", ["P01\n", "../P01", "/tmp/P01", ".P01", "P01/"])
def test_a_participant_id_that_is_not_a_name_is_refused_before_anything_is_written(tmp_path, capsys, participant):
    assert study_cli(tmp_path / "d", "run", "--participant", participant, "--simulated") == 2
    assert "participant id" in one_line(capsys.readouterr().err)
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize("field, value", [("name", "ex\n"), ("name", "../x"), ("name", "/tmp/x"), ("ids", ["P01\n"]),
                                          ("condition", "a\n"), ("condition", "../a")])
def test_study_and_condition_names_are_full_matches_of_the_one_rule(tmp_path, capsys, field, value):
    text = EXAMPLE.read_text()
    if field == "name":
        text = text.replace('name = "example"', f"name = {json.dumps(value)}", 1)
    elif field == "ids":
        text = text.replace("participants = 6 ", f"ids = {json.dumps(value)} ", 1)
    else:
        text = text.replace('name = "dt-task"', f"name = {json.dumps(value)}", 1)
    path = tmp_path / "study.toml"
    path.write_text(text)
    assert main(["study", "status", str(path), "--folder", str(tmp_path / "d")]) == 2
    error = one_line(capsys.readouterr().err)
    assert "is not accepted; a name is 1 to 64 letters, digits" in error


def test_a_participant_folder_linked_out_of_the_study_folder_is_refused(copy, tmp_path, capsys):
    outside = tmp_path / "elsewhere"
    (copy / "P01").rename(outside)
    os.symlink(outside, copy / "P01")
    before = checksums(outside)
    assert study_cli(copy, "run", "--participant", "P01", "--simulated", "--condition", "active", "--again") == 2
    assert "would be written outside its folder" in one_line(capsys.readouterr().err)
    assert checksums(outside) == before


# -- issue 42 case 1: typed text that is not Unicode text -----------------------------------------------------------
def _rerun_questionnaire(copy, typed: str):
    """P01's first session with its questionnaire still due, answered at the terminal by ``typed``."""
    study = dataclasses.replace(load_study(EXAMPLE), folder=copy)
    (copy / ANSWERS).unlink()
    out = io.StringIO()
    runner = ParticipantRun(study, "P01", False, input_stream=io.StringIO(typed), output_stream=out, viewer=False)
    return runner.run("dt-task"), out.getvalue()


def test_a_lone_surrogate_typed_in_the_questionnaire_is_refused_there_and_nothing_is_lost(copy, capsys):
    code, out = _rerun_questionnaire(copy, "5\n3\n\ud800zz\nit was fine\n")
    assert code == 0
    assert out.count("That text can't be recorded (character 1 is U+D800, half of a surrogate pair") == 1, out
    assert "Please type any Unicode text" in out and "Answers saved." in out
    rows = [json.loads(line) for line in (copy / ANSWERS).read_text(encoding="utf-8").splitlines()]
    assert [row["value"] for row in rows[1:]] == [5, 3, "it was fine"]  # the Likert answers kept, the text asked again
    assert not list(copy.rglob(".*.tmp"))
    assert study_cli(copy, "status") == 0
    assert "P01          dt-task: done" in capsys.readouterr().out


def test_the_input_ending_after_a_refused_text_saves_nothing_and_asks_again_later(copy):
    code, out = _rerun_questionnaire(copy, "5\n3\n\udcffx\n")
    assert code == 0 and "it is asked again when the run goes on" in out
    assert not (copy / ANSWERS).exists() and not list(copy.rglob(".*.tmp"))


class _Page:
    """The part of the page's teacher ``ask_web`` uses: each call gives the next form's values."""

    def __init__(self, *forms):
        self.forms, self.notes = list(forms), []

    def ask_screen(self, title, text, button, items):
        self.notes.append(text)
        return self.forms.pop(0)


def test_the_page_shows_the_questionnaire_again_with_the_reason_for_text_that_is_not_text():
    items = load_study(EXAMPLE).items
    page = _Page([6, None, "\ud83dabc"], [6, None, "abc"])
    answers = questionnaire.ask_web(items, page)
    assert [a["value"] for a in answers] == [6, None, "abc"]
    assert len(page.notes) == 2 and "item 3: character 1 is U+D83D" in page.notes[1]


def test_an_answer_that_cannot_be_encoded_leaves_no_file_and_no_temporary_file(tmp_path):
    path = tmp_path / "P01" / "1-x-questionnaire.jsonl"
    with pytest.raises(UnicodeEncodeError):
        questionnaire.save(path, {"study": "example"}, [{"item": "comments", "kind": "text", "value": "\ud800"}])
    assert not path.exists() and not list(tmp_path.rglob("*.tmp"))
