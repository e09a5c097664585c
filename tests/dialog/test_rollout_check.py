"""``teachbot learn-weights --check WEIGHTS`` on the real dialog loop, small (issue 49): output, exit codes, the fit."""

import json

import pytest

from dialog.cli import main
from learning.irl.rollout_check import CHECK_FILE

# the training allocation on small pools of calibration data (rendered once into the cache), 8 turns
SMALL_SUITE = """
name = "small-training"
description = "ch7-training's allocation, small"
kind = "episodes"
task = "prepare-lunch"
kitchen = "kitchen-1"
strategies = ["scripted-expert"]
datasets = 2
seeds = [31]
data_seed = 101
checkpoints = [8]
axis = "turns"

[dataset]
objects_per_scene = 8
pool_size = 24
test_size = 16

[costs]
label = 1
demo = 2
feature = 2
none = 0

[[condition]]
name = "training"
budget = 6
turns = 8
change_every = 4
"""


@pytest.fixture
def small(tmp_path):
    suite = tmp_path / "small-suite.toml"
    suite.write_text(SMALL_SUITE)
    settings = tmp_path / "check.toml"
    text = CHECK_FILE.read_text().replace('"dialog/suites/ch7-training.toml"', f'"{suite}"')
    settings.write_text(text.replace("datasets = 5", "datasets = 2"))
    return settings


def test_the_check_plays_both_on_the_same_episodes_and_prints_one_json_line(small, capsys):
    code = main(["learn-weights", "--check", "dt-task-env", "--check-settings", str(small), "--check-seeds", "31",
                 "--check-turns", "6", "--check-workers", "1", "--json"])
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1
    result = json.loads(lines[0])
    assert code == (0 if result["passes"] else 1)
    assert result["checked"] == "dt-task-env" and result["expert"] == "scripted-expert"
    assert result["allocation"]["turns"] == 6 and result["allocation"]["data_seed"] == 101
    ours, theirs = result["episodes"]["checked"], result["episodes"]["expert"]
    assert [(e["dataset"], e["seed"]) for e in ours] == [(e["dataset"], e["seed"]) for e in theirs] == [(0, 31),
                                                                                                         (1, 31)]
    for e in ours + theirs:
        assert sum(e["counts"].values()) == e["turns"] == 6 and len(e["spent_at"]) == 4
        assert list(e["spent_at"]) == sorted(e["spent_at"]) and e["spent_at"][-1] <= 6
        assert e["first_feature_turn"] is None or (e["counts"]["feature"] == 1 and 1 <= e["first_feature_turn"] <= 6)
    assert [c["name"] for c in result["criteria"]] == ["feature_query_early", "demonstrations", "end_accuracy"]
    assert result["passes"] == all(c["passes"] for c in result["criteria"])
    demo_gap = result["checked_summary"]["questions"]["demo"] - result["expert_summary"]["questions"]["demo"]
    assert result["criteria"][1]["value"] == pytest.approx(demo_gap)


def test_the_table_names_every_episode_the_criteria_and_the_verdict(small, tmp_path, capsys):
    from learning.decision.weights import WEIGHTS_DIRECTORY

    weights = tmp_path / "mine.toml"
    weights.write_text((WEIGHTS_DIRECTORY / "dt-task.toml").read_text())
    code = main(["learn-weights", "--check", str(weights), "--check-settings", str(small), "--check-seeds", "31",
                 "--check-datasets", "1", "--check-turns", "4", "--check-workers", "1"])
    out = capsys.readouterr().out
    assert "Rollout check of mine.toml beside scripted-expert" in out and "| d0 s31 | mine.toml |" in out
    assert "(a) feature query early" in out and "(c) end accuracy" in out
    assert out.strip().splitlines()[-1] == f"rollout check: {'PASS' if code == 0 else 'FAIL'}"


@pytest.mark.parametrize("argv, words", [
    (["--check", "dt-task-envv"], "accepted: a weights .toml file"),
    (["--check", "missing.toml"], "no weights file there"),
    (["--check", "dt-task-env", "--check-seeds", "3"], "one of the expert demonstrations' seeds 1-30"),
    (["--check", "dt-task-env", "--check-data-seed", "0"], "calibration data, data seed >= 101"),
    (["--check", "dt-task-env", "--demos", "shipped"], "--demos do(es) not apply"),
    ([], "--demos is required to fit"),
    (["--demos", "shipped", "--out", "never-written.toml", "--no-check", "--check-seeds", "31"],
     "--check-seeds set(s) the rollout check, which --no-check skips"),
])
def test_bad_input_is_one_line_and_exit_2(argv, words, capsys):
    assert main(["learn-weights", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err


def test_every_fit_runs_the_check_and_its_report_records_it(small, tmp_path, capsys):
    out, report = tmp_path / "w.toml", tmp_path / "report.json"
    code = main(["learn-weights", "--demos", "shipped", "--out", str(out), "--split-seeds", "0", "--fit-seeds", "0",
                 "--iterations", "2", "--report", str(report), "--check-settings", str(small),
                 "--check-seeds", "31", "--check-datasets", "1", "--check-turns", "4", "--json"])
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    recorded = json.loads(report.read_text())
    assert out.exists() and recorded["rollout_check"] == summary["rollout_check"]
    check, rule = summary["rollout_check"], summary["ship_rule"]
    assert rule["passes"] == check["passes"] and code == (0 if check["passes"] else 1)
    assert check["allocation"]["turns"] == 4 and len(check["criteria"]) == 3
