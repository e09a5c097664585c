"""The committed calibration rule for the hand-set DT presets, and the script that applies it (issue 39)."""

import json

import pytest

from dialog.experiments.calibration import (
    RULE_FILE,
    GridPreset,
    calibrate,
    choose,
    load_rule,
    plan_suites,
    write_choices,
)
from learning.decision.weights import preset_weights
from learning.decision.weights_file import load_weights
from learning.errors import DataFileError
from tests.scripts import load_script

TINY_RULE = """
[rule]
data_seeds = [100]
datasets = 1
seeds = [0]

[[preset]]
name = "dt-iros"
base = "dt-iros-v1"
feature = "class_distribution_uniformity"
grid = [0.0, 0.05]

[[condition]]
suite = "ch6-dynamic"
name = "rapid"
turns = 6
budget = 3
"""


def test_the_committed_rule_calibrates_dt_iros_and_dt_task_on_data_no_table_uses():
    rule = load_rule()
    assert [(p.name, p.base, p.feature) for p in rule.presets] == [
        ("dt-iros", "dt-iros-v1", "class_distribution_uniformity"),
        ("dt-task", "dt-task-v1", "class_distribution_uniformity")]
    assert all(seed >= 100 for seed in rule.data_seeds)
    assert rule.episodes == 2 * 6 * 3 * len(rule.data_seeds) * rule.datasets * len(rule.seeds)  # issue 53: 6 values
    assert all(0.05 < max(p.grid) for p in rule.presets)  # the grid brackets the first run's choice
    assert all(s.data_seed >= 100 and all(c.until_budget_spent for c in s.conditions) for s in plan_suites(rule))


def test_the_v1_presets_keep_the_hand_set_weights():
    assert list(preset_weights("dt-iros-v1")) == [1.0, 0.05, 0, 0, 0, 0, 0]
    assert list(preset_weights("dt-task-v1")) == [1.0, 0.05, 0.3, 0.1, 0, 0, 0]


def test_the_best_mean_wins_and_ties_go_to_the_smaller_weight():
    preset = GridPreset("dt-iros", "dt-iros-v1", "class_distribution_uniformity", (0.0, 0.0125, 0.025, 0.05))
    assert choose(preset, [0.80, 0.83, 0.82, 0.81], 1e-9) == 0.0125
    assert choose(preset, [0.80, 0.83, 0.83, 0.81], 1e-9) == 0.0125
    assert choose(preset, [0.83, 0.83, 0.83, 0.83], 1e-9) == 0.0


@pytest.mark.parametrize("change, message", [
    (("data_seeds = [100]", "data_seeds = [3]"), "data_seeds"),
    (('name = "rapid"', 'name = "slow"'), "has no condition 'slow'"),
    (("grid = [0.0, 0.05]", "grid = [0.05, 0.0]"), "increasing order"),
    (('base = "dt-iros-v1"', 'base = "dt-iros-v9"'), "base 'dt-iros-v9' is not one of"),
])
def test_a_bad_rule_is_one_message(tmp_path, change, message):
    path = tmp_path / "rule.toml"
    path.write_text(TINY_RULE.replace(*change))
    with pytest.raises(DataFileError, match=message):
        load_rule(path)


def test_a_tiny_rule_runs_picks_a_grid_value_and_writes_it_with_provenance(tmp_path):
    path = tmp_path / "rule.toml"
    path.write_text(TINY_RULE)
    rule = load_rule(path)
    choices, facts = calibrate(rule, tmp_path / "results", workers=1, progress=False, say=lambda _: None)
    assert facts["episodes"] == 2 and len(choices) == 1
    choice = choices[0]
    assert choice.episodes == (1, 1) and all(0 <= a <= 1 for a in choice.accuracies)
    assert choice.chosen == choose(choice.preset, list(choice.accuracies), 1e-9)
    written = write_choices(choices, rule, facts, tmp_path / "chosen")
    weights = load_weights(written[0])
    assert weights.as_dict()["class_distribution_uniformity"] == choice.chosen
    assert weights.provenance["rule_sha256"] == rule.sha256 and weights.provenance["data_seeds"] == "100"
    assert "0: " in weights.provenance["grid_mean_final_accuracy"]


def test_the_script_prints_the_plan_and_an_estimate_without_playing(tmp_path, capsys):
    script = load_script("calibrate_dt")
    assert script.main(script._parse(["--dry-run", "--json", "--workers", "2"])) == 0
    facts = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert facts["episodes"] == load_rule(RULE_FILE).episodes and facts["rule_sha256"] == load_rule().sha256
    assert facts["estimated_seconds"] is None or facts["estimated_seconds"] > 0


def test_a_missing_rule_or_a_bad_cost_file_is_one_message(tmp_path):
    script = load_script("calibrate_dt")
    with pytest.raises(DataFileError, match="no calibration rule file there"):
        script.main(script._parse(["--rule", str(tmp_path / "none.toml"), "--dry-run"]))
    cost = tmp_path / "cost.toml"
    cost.write_text('[[measured]]\ncondition = "ch6-static/static"\nseconds_per_episode = -1\n')
    with pytest.raises(DataFileError, match="seconds_per_episode"):
        script.seconds_per_episode(cost)
    assert script.seconds_per_episode()["ch6-static/static"] > 0  # the committed measurement
