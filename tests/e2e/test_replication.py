"""What ``teachbot learn-weights`` writes runs through the command line: demo, teach (resumed), regress (local, Ray)."""

import json

import pytest

from dialog.cli import main
from dialog.transcripts.jsonl import read_session
from learning.decision.weights_file import DecisionWeights, save_weights

pytestmark = pytest.mark.e2e
DT_TASK_LIKE = {"classifier_discriminability": 1.0, "class_distribution_uniformity": 0.05,
                "instance_variation": 0.3, "prediction_margin": 0.1, "budget_consumption": -0.5}


@pytest.fixture
def weights_file(tmp_path):
    weights = DecisionWeights(tuple(DT_TASK_LIKE), list(DT_TASK_LIKE.values()), {"method": "maxent-irl"})
    return save_weights(tmp_path / "mine.toml", weights, comment="written by the test as learn-weights would")


def last_json(capsys) -> dict:
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def test_demo_runs_dt_with_a_weights_file_and_records_it(tmp_path, capsys, weights_file):
    path = tmp_path / "demo.jsonl"
    assert main(["demo", "--weights", str(weights_file), "--turns", "6", "--budget", "8", "--change-every", "3",
                 "--transcript", str(path), "--json"]) == 0
    summary = last_json(capsys)
    assert summary["strategy"] == "dt" and summary["turns"] == 6
    header = read_session(path)[0]
    assert header["strategy"] == "dt"
    assert header["weights"] == {"file": str(weights_file.resolve()), "values": DT_TASK_LIKE}


def test_demo_refuses_weights_beside_a_strategy_without_weights(tmp_path, capsys, weights_file):
    assert main(["demo", "--weights", str(weights_file), "--strategy", "active", "--turns", "2",
                 "--transcript", str(tmp_path / "x.jsonl")]) == 2
    assert "--strategy active does not use weights" in capsys.readouterr().err
    assert not (tmp_path / "x.jsonl").exists()


def test_teach_resume_rebuilds_the_weights_and_refuses_a_changed_file(tmp_path, capsys, weights_file):
    path = tmp_path / "teach.jsonl"
    common = ["--teacher", "scripted", "--no-pictures", "--json"]
    assert main(["teach", "--weights", str(weights_file), "--turns", "6", "--budget", "8", "--change-every", "3",
                 "--transcript", str(path), *common]) == 0
    whole = last_json(capsys)
    full = path.read_text().splitlines()
    path.write_text("\n".join(full[:4]) + "\n")  # the header and three turns: stopped half-way
    assert main(["teach", "--resume", str(path), "--json"]) == 0
    resumed = last_json(capsys)
    assert resumed["strategy"] == "dt" and resumed["queries"] == whole["queries"]
    assert resumed["accuracy"] == whole["accuracy"]

    path.write_text("\n".join(full[:4]) + "\n")
    weights_file.write_text(weights_file.read_text().replace("budget_consumption = -0.5", "budget_consumption = -2.0"))
    assert main(["teach", "--resume", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"the weights file {weights_file.resolve()} changed since the session was recorded" in err
    assert main(["teach", "--resume", str(path), "--weights", str(tmp_path / "other.toml")]) == 2
    assert "--weights" in capsys.readouterr().err


def test_regress_smoke_with_a_user_strategy(tmp_path, capsys, weights_file):
    out = tmp_path / "smoke"
    assert main(["regress", "--suite", "smoke", "--weights", f"mine={weights_file}", "--results", str(out),
                 "--workers", "2", "--no-progress", "--check", "--json"]) == 0
    summary = last_json(capsys)
    assert summary["passed"] and summary["data_seed"] == 0 and summary["episodes"] == 15  # 5 strategies x 3 sets
    report = (out / "report.md").read_text()
    assert "| mine |" in report and f"strategy `mine`: DT with the weights in {weights_file.resolve()}" in report
    header = read_session(out / "transcripts" / "static" / "mine-d0-s0.jsonl")[0]
    assert header["strategy"] == "mine"


def test_regress_on_ray_carries_the_weights_and_the_data_seed(tmp_path, capsys, weights_file):
    ray = pytest.importorskip("ray", reason="the optional Ray extra is not installed")
    suite = tmp_path / "tiny.toml"
    suite.write_text('name = "tiny-ray"\nstrategies = ["passive"]\ndatasets = 1\ncheckpoints = [1, 2]\n'
                     '[dataset]\npool_size = 24\ntest_size = 24\n'
                     '[[condition]]\nname = "static"\nbudget = 3\nturns = 4\nchange_every = 2\n')
    args = ["regress", "--suite", str(suite), "--weights", f"mine={weights_file}", "--data-seed", "3",
            "--no-progress", "--json"]
    try:
        assert main([*args, "--results", str(tmp_path / "ray"), "--ray", "local"]) == 0
    finally:
        ray.shutdown()
    assert last_json(capsys)["data_seed"] == 3
    assert main([*args, "--results", str(tmp_path / "local"), "--workers", "1"]) == 0
    capsys.readouterr()
    rows = [(tmp_path / name / "episodes.csv").read_text().splitlines() for name in ("ray", "local")]
    assert [[",".join(r.split(",")[:10]) for r in table] for table in rows][0] == \
        [",".join(r.split(",")[:10]) for r in rows[1]]
    assert [r.split(",")[1] for r in rows[0][1:]] == ["passive", "mine"]


def test_weights_that_can_never_ask_are_warned_about_in_one_line(tmp_path, capsys):
    """Issue 23 case 2: seven zero weights (what a fit that learned nothing writes) ran 30 silent turns unremarked."""
    zeros = {name: 0.0 for name in DT_TASK_LIKE} | {"remaining_time": 3.0}  # RT alone ties every candidate
    path = save_weights(tmp_path / "zeros.toml", DecisionWeights(tuple(zeros), list(zeros.values()), {}), comment="")
    assert main(["demo", "--weights", str(path), "--turns", "3", "--transcript", str(tmp_path / "d.jsonl")]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "never asks" in line]
    assert len(warned) == 1 and warned[0].startswith(f"warning: {path.resolve()}:")
    assert main(["regress", "--suite", "smoke", "--weights", f"zeros={path}", "--results", str(tmp_path / "r"),
                 "--no-progress"]) == 0
    assert sum("never asks" in line for line in capsys.readouterr().err.splitlines()) == 1


def test_teach_takes_weights_with_the_expert_habit_features(tmp_path, capsys):
    """What `learn-weights` writes by default since issue 27 names eleven features (the seven and the habits);
    teach records them in the header and resumes from it (the header check once knew only the seven)."""
    from pathlib import Path

    shipped = Path(__file__).resolve().parents[2] / "learning" / "decision" / "presets" / "dt-task-env-v1.toml"
    path = tmp_path / "teach.jsonl"
    assert main(["teach", "--weights", str(shipped), "--turns", "4", "--budget", "8", "--change-every", "2",
                 "--transcript", str(path), "--teacher", "scripted", "--no-pictures", "--json"]) == 0
    whole = last_json(capsys)
    header = read_session(path)[0]
    assert len(header["weights"]["values"]) == 11 and "pace_overrun" in header["weights"]["values"]
    path.write_text("\n".join(path.read_text().splitlines()[:3]) + "\n")
    assert main(["teach", "--resume", str(path), "--json"]) == 0
    assert last_json(capsys)["accuracy"] == whole["accuracy"]
