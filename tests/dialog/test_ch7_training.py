"""The ch7-training suite (issue 15): its stored baseline shows the scripted expert ahead, and `--check` passes.

The whole suite is 300 episodes; the check runs the expert and DT-task on every seed and data set, which the
baseline covers exactly (episodes are deterministic by seed, so a strategy subset reproduces its stored means).
"""

import json

from dialog.cli import main
from dialog.experiments.baseline import BASELINE_DIR
from dialog.experiments.suite import load_suite
from learning.strategies import STRATEGY_NAMES

SUITE = load_suite("ch7-training", known_strategies=STRATEGY_NAMES)
STORED = json.loads((BASELINE_DIR / "ch7-training.json").read_text())


def test_the_suite_is_the_thesis_training_condition_on_fresh_seeds_and_data():
    (condition,) = SUITE.conditions
    assert (SUITE.task, condition.budget, condition.turns, condition.change_every) == ("prepare-lunch", 15, 30, 10)
    assert SUITE.costs == {"label": 1, "demo": 2, "feature": 2, "none": 0}
    assert SUITE.strategies == ("scripted-expert", "active", "dt-iros", "dt-task", "dt-task-env")
    assert len(SUITE.seeds) >= 10 and min(SUITE.seeds) >= 100 and SUITE.data_seed == 100  # never the ch7 suite's
    assert {(f.better, *f.than) for f in SUITE.findings} == {("scripted-expert", other)
                                                             for other in ("active", "dt-iros", "dt-task")}


def test_the_stored_baseline_shows_the_expert_ahead_at_the_end():
    assert (STORED["seeds"], STORED["datasets"]) == (list(SUITE.seeds), SUITE.datasets)
    bands = STORED["bands"]["training"]
    assert set(bands) == set(SUITE.strategies)
    expert = bands["scripted-expert"]["30"]
    for other in ("active", "dt-iros", "dt-task"):
        assert expert["mean"] > bands[other]["30"]["band"][1], other  # above the other's whole band


def test_check_passes_on_the_stored_baseline(tmp_path, capsys):
    code = main(["regress", "--suite", "ch7-training", "--strategies", "scripted-expert", "dt-task",
                 "--results", str(tmp_path / "run"), "--workers", "2", "--no-progress", "--check", "--json"])
    out = capsys.readouterr().out
    summary = json.loads(out.strip().splitlines()[-1])
    assert code == 0 and summary["passed"] and summary["failures"] == [], out
    assert summary["episodes"] == 2 * len(SUITE.seeds) * SUITE.datasets
    assert "e3-expert-beats-dt-task: holds" in out
