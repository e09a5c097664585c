"""A real episode in PyBullet through the command line."""

import json

import pytest

from dialog.cli import main
from dialog.transcripts.jsonl import read_transcript

pytestmark = pytest.mark.e2e


def run_demo(capsys, path, *extra):
    code = main(["demo", "--turns", "8", "--budget", "10", "--change-every", "4", "--transcript", str(path),
                 "--json", *extra])
    assert code == 0
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def test_demo_runs_and_prints_a_json_summary(tmp_path, capsys):
    summary = run_demo(capsys, tmp_path / "run.jsonl", "--seed", "2")
    assert set(summary) == {"seed", "strategy", "turns", "budget_spent", "queries", "accuracy", "transcript",
                            "seconds"}
    assert summary["turns"] == 8 and summary["budget_spent"] <= 10
    assert set(summary["queries"]) == {"label", "demo", "feature", "none"} and sum(summary["queries"].values()) == 8
    records = read_transcript(tmp_path / "run.jsonl")  # one record per turn after the session header
    assert len(records) == 8 and len((tmp_path / "run.jsonl").read_text().splitlines()) == 9
    gestures = [record["gesture"] for record in records if "gesture" in record]
    assert gestures and all(g["reached"] and g["horizontal_error_m"] < 0.02 for g in gestures)


def test_same_seed_twice_gives_byte_identical_transcripts(tmp_path, capsys):
    run_demo(capsys, tmp_path / "a.jsonl", "--seed", "9", "--strategy", "passive")
    run_demo(capsys, tmp_path / "b.jsonl", "--seed", "9", "--strategy", "passive")
    run_demo(capsys, tmp_path / "c.jsonl", "--seed", "10", "--strategy", "passive")
    first, second = (tmp_path / "a.jsonl").read_bytes(), (tmp_path / "b.jsonl").read_bytes()
    assert first == second
    assert first != (tmp_path / "c.jsonl").read_bytes()


def test_bad_arguments_are_rejected_with_a_message(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--strategy", "clever"])
    assert "--strategy: 'clever' is not one of the accepted names: " in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["demo", "--turns", "0"])
    assert "at least 1" in capsys.readouterr().err


def test_the_summary_counts_questions_in_words_and_the_json_keeps_its_counts(tmp_path, capsys):
    from dialog.commands._summary import questions_in_words

    assert main(["demo", "--turns", "6", "--budget", "6", "--change-every", "3", "--transcript",
                 str(tmp_path / "w.jsonl"), "--json"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    summary = json.loads(lines[-1])
    assert summary["strategy"] == "dt-task"  # the demo's default
    assert set(summary["queries"]) == {"label", "demo", "feature", "none"}
    assert f"questions: {questions_in_words(summary['queries'])};" in lines[-2]
    assert "{'" not in lines[-2]
    assert "; 12 objects a scene (an interactive size; the thesis's experiments use 55);" in lines[-2]


def test_default_transcript_names_say_what_differs_from_the_defaults(tmp_path, monkeypatch):
    """Issue 23 case 11: the embodied demo wrote runs/demo-dt-task-seed0.jsonl over the plain demo's transcript."""
    monkeypatch.chdir(tmp_path)  # no earlier demo here, so no name is numbered
    from dialog.cli import build_parser
    from dialog.commands.demo import default_transcript
    parse = build_parser().parse_args
    assert str(default_transcript(parse(["demo"]), None)) == "runs/demo-dt-task-seed0.jsonl"  # unchanged
    assert str(default_transcript(parse(["demo", "--embodied-costs"]), 600.0)) == \
        "runs/demo-dt-task-embodied-600s-seed0.jsonl"
    assert str(default_transcript(parse(["demo", "--task", "prepare-lunch", "--seed", "3"]), None)) == \
        "runs/demo-dt-task-prepare-lunch-seed3.jsonl"


def test_an_embodied_demo_is_scored_at_the_allocations_end_and_shows_its_clock(tmp_path, capsys):
    """Issue 42, case 6: the accuracy came from a turn that ended past --time 60s, and no line showed seconds."""
    from dialog.cli import main

    path = tmp_path / "e.jsonl"
    assert main(["demo", "--embodied-costs", "--time", "60s", "--transcript", str(path), "--json"]) == 0
    out = capsys.readouterr().out
    records = [json.loads(line) for line in path.read_text().splitlines()][1:]
    within = [r for r in records if r["ended"] <= 60]
    assert records[-1]["ended"] > 60 and records[-1]["accuracy"] != within[-1]["accuracy"]  # the crossing turn
    assert json.loads(out.strip().splitlines()[-1])["accuracy"] == within[-1]["accuracy"]
    assert f"held-out scenes after 60 s (turn {within[-1]['turn']}, the last that ended within them): " \
           f"{within[-1]['accuracy']:.1%}" in out
    assert "Turn   1 at 0.0 s · " in out and f"Turn   2 at {records[1]['time']:.1f} s · " in out
