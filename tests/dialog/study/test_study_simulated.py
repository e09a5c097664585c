"""The shipped example study, dry-run with --simulated for a few participants: run, status, report."""

import csv
import dataclasses
import json
import shutil
from pathlib import Path

import pytest

from dialog.cli import main
from dialog.study.design import assigned_orders
from dialog.study.files import session_files
from dialog.study.studyfile import load_study
from dialog.study.tables import refused_attempts
from dialog.transcripts.jsonl import read_session

EXAMPLE = Path(__file__).resolve().parents[3] / "dialog" / "data" / "studies" / "example.toml"
PARTICIPANTS = ("P01", "P02", "P03")


def study_cli(folder, *args):
    return main(["study", args[0], str(EXAMPLE), "--folder", str(folder), *args[1:]])


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("study") / "records"
    for participant in PARTICIPANTS:
        assert study_cli(folder, "run", "--participant", participant, "--simulated") == 0
    return folder


def test_every_session_is_recorded_with_the_study_header(folder):
    study = dataclasses.replace(load_study(EXAMPLE), folder=folder)
    for participant in PARTICIPANTS:
        for position, name in enumerate(assigned_orders(study)[participant], start=1):
            files = session_files(study, participant, position, name)
            header, records = read_session(files.transcript)
            assert header["study"] == {"study": "example", "participant": participant, "condition": name,
                                       "order": position, "software": "teachbot 0.1.0", "simulated": True}
            assert header["strategy"] == study.condition(name).strategy
            assert len(records) == study.condition(name).turns
            lines = files.questionnaire.read_text().splitlines()
            assert json.loads(lines[0])["questionnaire"] == header["study"]
            assert [json.loads(line)["item"] for line in lines[1:]] == ["ease", "smart", "comments"]


def test_a_participant_who_is_done_is_refused_unless_asked(folder, capsys):
    assert study_cli(folder, "run", "--participant", "P01", "--simulated") == 2
    err = capsys.readouterr().err
    assert "already done every session" in err
    assert f"(see teachbot study status {EXAMPLE} --folder {folder}); to run one again" in err  # runs as printed
    assert study_cli(folder, "run", "--participant", "P01", "--simulated", "--condition", "active") == 2
    assert "--again" in capsys.readouterr().err
    assert study_cli(folder, "run", "--participant", "Jane Doe", "--simulated") == 2
    assert "not accepted" in capsys.readouterr().err
    assert study_cli(folder, "run", "--participant", "P99", "--simulated") == 2
    assert "not in the study" in capsys.readouterr().err


def test_an_interrupted_participant_resumes_where_they_stopped(folder, tmp_path):
    copy = tmp_path / "records"
    shutil.copytree(folder, copy)
    person = copy / "P02"
    order = assigned_orders(load_study(EXAMPLE))["P02"]
    second = person / f"2-{order[1]}.jsonl"
    complete = second.read_text()
    lines = complete.splitlines(keepends=True)
    second.write_text("".join(lines[:4]) + lines[4][:30])  # three turns, then a crash mid-line
    (person / f"2-{order[1]}-questionnaire.jsonl").unlink()
    for path in person.glob(f"3-{order[2]}*"):
        path.unlink()
    assert study_cli(copy, "run", "--participant", "P02", "--simulated") == 0
    assert second.read_text() == complete  # the resumed session repeats the interrupted one exactly
    assert (person / f"3-{order[2]}.jsonl").read_text() == (folder / "P02" / f"3-{order[2]}.jsonl").read_text()
    assert (person / f"1-{order[0]}.jsonl").stat().st_mtime == (folder / "P02" / f"1-{order[0]}.jsonl").stat().st_mtime


def test_a_condition_run_again_keeps_the_old_records(folder, tmp_path, capsys):
    copy = tmp_path / "records"
    shutil.copytree(folder, copy)
    first = assigned_orders(load_study(EXAMPLE))["P03"][0]
    assert study_cli(copy, "run", "--participant", "P03", "--simulated", "--condition", first, "--again") == 0
    kept = [line for line in capsys.readouterr().out.splitlines() if line.startswith("Kept the earlier records")]
    assert kept == [f"Kept the earlier records of session 1 (2 files, renamed *.superseded-N in {copy / 'P03'})."]
    again = copy / "P03" / f"1-{first}.jsonl"
    assert again.with_name(f"{again.name}.superseded-1").read_text() == again.read_text()  # same seed, same session


def test_status_and_report_of_a_partly_run_study(folder, tmp_path, capsys):
    copy = tmp_path / "records"
    shutil.copytree(folder, copy)
    assert study_cli(copy, "run", "--participant", "P04", "--abort", "fire alarm") == 0
    capsys.readouterr()
    assert study_cli(copy, "status") == 0
    status = capsys.readouterr().out
    assert "9 done" in status and "1 aborted" in status and "fire alarm" in status
    assert "orders of the 3 participants who finished every session: positions balanced, carry-over not" in status
    rows = [line for line in status.splitlines() if line.startswith("P0")]
    assert len(rows) == 6 and all(line.count(": ") == 3 for line in rows)  # one line per participant, no wrapping
    assert "ABORTED" in rows[3] and max(len(line) for line in rows) <= 100

    assert study_cli(copy, "report", "--out", str(tmp_path / "report")) == 0
    report = tmp_path / "report"
    with open(report / "turns.csv") as handle:
        turns = list(csv.DictReader(handle))
    recorded = sum(len(read_session(path)[1]) for path in copy.glob("P0*/[1-9]-*.jsonl")
                   if "questionnaire" not in path.name)
    assert len(turns) == recorded == 3 * 3 * 8  # one row per recorded turn of a condition (not the practice round)
    assert set(turns[0]) >= {"participant", "condition", "order", "turn", "action", "cost", "answer",
                             "answer_seconds", "refused", "accuracy"}
    with open(report / "questionnaire.csv") as handle:
        assert len(list(csv.DictReader(handle))) == 9 * 3
    text = (report / "report.md").read_text()
    assert "| final accuracy | dt-task vs active | 3 |" in text
    assert "| P04 | 1 | dt-small-budget | aborted | fire alarm |" in text
    assert "## Order effects" in text
    for png in ("study-example-curves.png", "study-example-final.png"):
        assert (report / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_refused_attempts_count_unreadable_lines_only():
    assert refused_attempts({"kind": "answer", "lines": ["blue?", "why", "a fruit"]}) == 1
    assert refused_attempts({"kind": "answer", "lines": ["a fruit"]}) == 0
    assert refused_attempts({"kind": "late", "lines": ["zzz"]}) == 1
    assert refused_attempts({"kind": "none", "lines": []}) == 0


def test_a_records_folder_that_cannot_be_written_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    assert study_cli(blocker / "records", "run", "--participant", "P01", "--simulated") == 2
    error = capsys.readouterr().err.strip()
    assert "cannot write the participant's folder" in error and "is a file, not a folder" in error
    assert "\n" not in error


def test_a_report_before_anyone_ran_lists_every_session_missing(tmp_path, capsys):
    assert study_cli(tmp_path / "records", "report", "--out", str(tmp_path / "report")) == 0
    text = (tmp_path / "report" / "report.md").read_text()
    assert text.count("| missing |") == 18 and "0 of 18 sessions finished" in text
    assert (tmp_path / "report" / "turns.csv").read_text().count("\n") == 1  # the header only


def test_a_transcript_moved_to_another_session_is_refused(folder, tmp_path, capsys):
    copy = tmp_path / "records"
    shutil.copytree(folder, copy)
    first, second = sorted(p for p in (copy / "P01").glob("[12]-*.jsonl") if "questionnaire" not in p.name)
    first_text = first.read_text()
    first.write_text(second.read_text())
    second.write_text(first_text)
    assert study_cli(copy, "status") == 0  # the study's status is still shown; the two sessions are marked damaged
    shown = capsys.readouterr().out
    assert f"damaged: P01 session 1 (dt-task): {first}: line 1: the header's study condition" in shown
    assert "was it moved, renamed or edited?" in shown and "2 damaged" in shown
    assert study_cli(copy, "run", "--participant", "P01", "--simulated", "--condition", "dt-task") == 2
    error = capsys.readouterr().err
    assert str(first) in error and "is damaged, so nothing was written" in error and error.count("\n") == 1


def test_a_dry_run_goes_to_its_own_folder_and_says_simulated_everywhere(tmp_path, monkeypatch, capsys):
    """Issue 23 case 4: --simulated wrote where real participants go, and nothing said the sessions were simulated."""
    monkeypatch.chdir(tmp_path)
    assert main(["study", "run", str(EXAMPLE), "--participant", "P01", "--simulated", "--no-viewer"]) == 0
    real, dry = Path("runs/studies/example"), Path("runs/studies/example-simulated")
    assert (dry / "P01").is_dir() and not real.exists()
    assert main(["study", "report", str(EXAMPLE), "--simulated"]) == 0
    with open(dry / "report" / "turns.csv") as handle:
        assert {row["simulated"] for row in csv.DictReader(handle)} == {"True"}
    with open(dry / "report" / "questionnaire.csv") as handle:
        assert {row["simulated"] for row in csv.DictReader(handle)} == {"True"}
    assert "**All of the 3 recorded sessions are simulated" in (dry / "report" / "report.md").read_text()


def test_a_report_over_simulated_and_real_sessions_refuses_unless_asked(folder, tmp_path, capsys):
    copy = tmp_path / "records"
    shutil.copytree(folder, copy)
    first = assigned_orders(dataclasses.replace(load_study(EXAMPLE), folder=copy))["P01"][0]
    real = copy / "P01" / f"1-{first}.jsonl"
    lines = real.read_text().splitlines()
    header = json.loads(lines[0])
    header["session"]["study"]["simulated"] = False  # as a participant's own session would record it,
    header["session"]["teacher"] = {"kind": "terminal"}  # with the person at the terminal as its teacher
    real.write_text("\n".join([json.dumps(header)] + lines[1:]) + "\n")
    answers = real.with_name(f"1-{first}-questionnaire.jsonl")
    lines = answers.read_text().splitlines()
    header = json.loads(lines[0])
    header["questionnaire"]["simulated"] = False
    answers.write_text("\n".join([json.dumps(header)] + lines[1:]) + "\n")
    capsys.readouterr()
    assert study_cli(copy, "report", "--out", str(tmp_path / "report")) == 2
    error = capsys.readouterr().err.strip()
    assert "holds 8 simulated (dry-run) and 1 real sessions" in error and "--allow-mixed" in error
    assert study_cli(copy, "report", "--out", str(tmp_path / "report"), "--allow-mixed") == 0
    assert "**8 of the 9 recorded sessions are simulated" in (tmp_path / "report" / "report.md").read_text()


def test_status_and_report_of_the_real_folder_after_a_dry_run_name_the_simulated_folder(tmp_path, monkeypatch,
                                                                                        capsys):
    """Issue 42 case 5: after the docs' dry run, ``study report STUDY.toml`` wrote an empty report and said
    nothing of the simulated sessions in ``<folder>-simulated``."""
    monkeypatch.chdir(tmp_path)
    study = tmp_path / "my study.toml"
    study.write_text(EXAMPLE.read_text().replace("turns = 8", "turns = 2"))
    shutil.copy(EXAMPLE.with_name("example-consent.txt"), tmp_path)  # the consent text, beside the study file
    assert main(["study", "run", str(study), "--participant", "P01", "--simulated"]) == 0
    capsys.readouterr()
    for action in ("report", "status"):
        command = f"teachbot study {action} '{study}' --simulated"
        assert main(["study", action, str(study)]) == 0
        notes = [line for line in capsys.readouterr().out.splitlines() if line.startswith("note: ")]
        assert notes == [f"note: no session is recorded in runs/studies/example; the simulated sessions (study run "
                         f"--simulated) are in runs/studies/example-simulated: {command}"]
    for args in (["--simulated"], ["--folder", "runs/studies/example"]):  # asked for: no note
        assert main(["study", "report", str(study), *args]) == 0
        assert "note: " not in capsys.readouterr().out
