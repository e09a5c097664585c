"""Consent and the practice round (issue 50, item 2): asked before anything is recorded, recorded once, the practice
apart from the conditions (byte-identical condition transcripts with or without it), known to resume, --again,
status and report; a damaged or missing consent record marks the participant damaged."""

from __future__ import annotations

import dataclasses
import io
import json
import re
import shutil
from pathlib import Path

import pytest

from dialog.cli import main
from dialog.study import consent
from dialog.study.files import session_state_of
from dialog.study.run import ParticipantRun
from dialog.study.status import status_text
from dialog.study.studyfile import load_study
from learning.errors import DataFileError

EXAMPLE = Path(__file__).resolve().parents[3] / "dialog" / "data" / "studies" / "example.toml"


def study_cli(study_file, folder, *args):
    return main(["study", args[0], str(study_file), "--folder", str(folder), *map(str, args[1:])])


def without(tmp_path: Path, *tables: str) -> Path:
    """A copy of the example study without its consent line and [practice] table (``tables`` says which)."""
    text = EXAMPLE.read_text()
    if "consent" in tables:
        text = re.sub(r"(?m)^consent = .*\n", "", text)
    if "practice" in tables:
        text = re.sub(r"(?ms)^\[practice\].*?(?=^\[\[conditions\]\])", "", text)
    path = tmp_path / "study.toml"
    path.write_text(text)
    shutil.copy(EXAMPLE.with_name("example-consent.txt"), tmp_path)
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """P01 dry-run with the example study as shipped, and with a copy that has no practice round."""
    base = tmp_path_factory.mktemp("consent")
    plain = without(base, "practice")
    assert study_cli(EXAMPLE, base / "with", "run", "--participant", "P01", "--simulated") == 0
    assert study_cli(plain, base / "without", "run", "--participant", "P01", "--simulated") == 0
    return base


def test_every_condition_transcript_is_byte_identical_with_or_without_the_practice_round(runs):
    with_practice, without_practice = runs / "with" / "P01", runs / "without" / "P01"
    names = sorted(path.name for path in without_practice.glob("[1-9]-*.jsonl"))
    assert len(names) == 6  # three transcripts, three questionnaires
    for name in names:
        assert (with_practice / name).read_bytes() == (without_practice / name).read_bytes(), name
    assert (with_practice / "0-practice.jsonl").exists() and not (without_practice / "0-practice.jsonl").exists()
    header = json.loads((with_practice / "0-practice.jsonl").read_text().splitlines()[0])["session"]
    assert header["study"]["condition"] == "practice" and header["study"]["order"] == 0 and header["turns"] == 3


def test_a_simulated_run_records_that_consent_was_not_asked(runs, capsys):
    record = json.loads((runs / "with" / "P01" / consent.CONSENT_FILE).read_text())["consent"]
    study = load_study(EXAMPLE)
    assert record["given"] == "simulated" and record["simulated"] is True
    assert record["text_sha256"] == study.consent.sha256 and record["text"] == "example-consent.txt"
    study = dataclasses.replace(study, folder=runs / "with", simulated=True)
    text = status_text(study)
    assert "consent (example-consent.txt): simulated: P01; not asked yet: P02" in text
    assert "practice round (not in the report's tables): done: P01; missing: P02" in text
    assert "3 done" in text


def test_the_report_counts_the_practice_round_and_leaves_it_out_of_its_tables(runs, tmp_path):
    assert study_cli(EXAMPLE, runs / "with", "report", "--out", tmp_path / "a") == 0
    assert study_cli(without(tmp_path, "practice"), runs / "without", "report", "--out", tmp_path / "b") == 0
    for table in ("turns.csv", "questionnaire.csv"):
        assert (tmp_path / "a" / table).read_text() == (tmp_path / "b" / table).read_text()
    report = (tmp_path / "a" / "report.md").read_text()
    assert "Practice rounds: 1 finished" in report and "left out of every table" in report
    assert "Consent (example-consent.txt): 1 simulated, 5 not asked yet." in report
    tables = [line for line in report.splitlines() if line.startswith("|")]
    assert tables == [line for line in (tmp_path / "b" / "report.md").read_text().splitlines()
                      if line.startswith("|")]


def person(tmp_path: Path, typed: str, participant: str = "P02"):
    study = dataclasses.replace(load_study(EXAMPLE), folder=tmp_path / "rec")
    out = io.StringIO()
    runner = ParticipantRun(study, participant, False, input_stream=io.StringIO(typed), output_stream=out,
                            viewer=False)
    return study, runner, out


def test_declining_records_only_the_declined_note_and_a_run_without_input_records_nothing(tmp_path):
    study, runner, out = person(tmp_path, "maybe\nno\n")
    assert runner.run() == 0
    assert "Please type 'yes'" in out.getvalue() and "did not agree" in out.getvalue()
    assert sorted(p.name for p in (tmp_path / "rec" / "P02").iterdir()) == [consent.DECLINED_FILE]
    note = json.loads((tmp_path / "rec" / "P02" / consent.DECLINED_FILE).read_text())["declined"]
    assert note["participant"] == "P02" and note["text_sha256"] == study.consent.sha256
    assert consent.consent_state(study, "P02") == "declined"
    study, runner, out = person(tmp_path, "", "P03")
    assert runner.run() == 1
    assert "standard input ended): nothing was recorded" in out.getvalue()
    assert not (tmp_path / "rec" / "P03").exists() or not any((tmp_path / "rec" / "P03").iterdir())


def test_agreeing_is_recorded_once_and_a_damaged_or_missing_record_marks_the_participant_damaged(runs, tmp_path,
                                                                                                capsys):
    study, runner, out = person(tmp_path, "yes\n")  # then the input ends at the practice round's "Press Enter"
    runner.run()
    record = json.loads((tmp_path / "rec" / "P02" / consent.CONSENT_FILE).read_text())["consent"]
    assert record["given"] == "terminal" and record["simulated"] is False
    assert consent.consent_state(study, "P02") == "agreed"
    first = (tmp_path / "rec" / "P02" / consent.CONSENT_FILE).read_bytes()
    study, runner, out = person(tmp_path, "")
    runner.run()  # a resumed run does not ask again
    assert consent.QUESTION not in out.getvalue()
    assert (tmp_path / "rec" / "P02" / consent.CONSENT_FILE).read_bytes() == first

    copy = tmp_path / "copy"
    shutil.copytree(runs / "with", copy)
    study = dataclasses.replace(load_study(EXAMPLE), folder=copy, simulated=True)
    path = copy / "P01" / consent.CONSENT_FILE
    path.write_text(path.read_text().replace(study.consent.sha256, "0" * 64))
    states = [session_state_of(study, "P01", position, name) for position, name in
              ((0, "practice"), (1, "dt-task"))]
    assert all(state.state == "damaged" and "SHA-256" in state.reason for state in states)
    assert "DAMAGED" in status_text(study)
    path.unlink()
    state = session_state_of(study, "P01", 1, "dt-task")
    assert state.state == "damaged" and "consent.json: missing, but 0-practice.jsonl is recorded" in state.reason
    capsys.readouterr()
    assert study_cli(EXAMPLE, copy, "run", "--participant", "P01", "--simulated") == 2
    assert "is damaged, so nothing was written" in capsys.readouterr().err


def test_the_practice_round_runs_again_only_when_asked_and_keeps_the_old_record(runs, tmp_path, capsys):
    copy = tmp_path / "copy"
    shutil.copytree(runs / "with", copy)
    old = (copy / "P01" / "0-practice.jsonl").read_bytes()
    assert study_cli(EXAMPLE, copy, "run", "--participant", "P01", "--simulated", "--condition", "practice") == 2
    assert "already did condition 'practice'" in capsys.readouterr().err
    assert study_cli(EXAMPLE, copy, "run", "--participant", "P01", "--simulated", "--condition", "practice",
                     "--again") == 0
    assert (copy / "P01" / "0-practice.jsonl.superseded-1").read_bytes() == old
    assert (copy / "P01" / "0-practice.jsonl").read_bytes() == old  # the same seed: the same round


def test_an_interrupted_practice_round_resumes_before_the_first_condition(runs, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(runs / "with", copy)
    for path in (copy / "P01").glob("[1-9]-*"):
        path.unlink()
    practice = copy / "P01" / "0-practice.jsonl"
    complete = practice.read_bytes()
    practice.write_bytes(b"".join(complete.splitlines(keepends=True)[:2]))  # the header and one turn
    assert study_cli(EXAMPLE, copy, "run", "--participant", "P01", "--simulated") == 0
    assert practice.read_bytes() == complete
    assert (copy / "P01" / "1-dt-task.jsonl").read_bytes() == (runs / "with" / "P01" / "1-dt-task.jsonl").read_bytes()


@pytest.mark.parametrize("change, message", [
    (("consent = \"example-consent.txt\"", "consent = \"nothing.txt\""), "'consent' names .*nothing.txt, which is "
                                                                         "missing; accepted: the name of a UTF-8"),
    (("consent = \"example-consent.txt\"", "consent = \"../x.txt\""), "'consent' '../x.txt' is not accepted"),
    (("consent = \"example-consent.txt\"", "consent = 3"), "'consent' 3 is not accepted"),
    (("turns = 3\nbudget = 10", "turns = 30\nbudget = 10"), r"\[practice\]: 'turns' must be .*10"),
    (("[practice]", "[practice]\nname = \"warm-up\""), r"\[practice\]: .*'name'"),
    (("name = \"active\"", "name = \"practice\""), "name 'practice' is taken by the practice round; accepted: any "
                                                  "other name"),
])
def test_a_bad_consent_or_practice_field_gets_one_message_naming_it(tmp_path, change, message):
    shutil.copy(EXAMPLE.with_name("example-consent.txt"), tmp_path)
    path = tmp_path / "study.toml"
    text = EXAMPLE.read_text()
    assert change[0] in text
    path.write_text(text.replace(change[0], change[1], 1))
    with pytest.raises(DataFileError, match=message) as error:
        load_study(path)
    assert "\n" not in str(error.value)


def test_a_consent_text_that_is_not_utf8_or_is_empty_is_refused(tmp_path):
    path = tmp_path / "study.toml"
    path.write_text(EXAMPLE.read_text())
    (tmp_path / "example-consent.txt").write_bytes(b"\xff\xfe")
    with pytest.raises(DataFileError, match="not UTF-8 text"):
        load_study(path)
    (tmp_path / "example-consent.txt").write_text("  \n")
    with pytest.raises(DataFileError, match="is empty"):
        load_study(path)
