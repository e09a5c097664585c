"""IRL's rollouts of the real dialog loop (thesis eq. 7.7): deterministic by seed, wherever they run; the CLI fit."""

from dataclasses import replace

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments.irl_rollouts import (
    TRAIN_SEED_BASE,
    VALIDATION_SEED_BASE,
    RolloutPool,
    RolloutTask,
    TrainingCondition,
    play,
    rollout_functions,
    training_condition,
    training_seed,
    validation_seeds,
)
from dialog.experiments.suite import Condition
from learning.decision.features import FEATURE_NAMES
from learning.decision.habits import EXTENDED_FEATURE_NAMES
from learning.decision.weights_file import load_weights
from learning.errors import SettingsError

# the training condition on small pools (rendered once into the cache) and a short episode
SMALL = replace(TrainingCondition(), condition=Condition("training", 6.0, 8, 4), datasets=2,
                plan=(("objects_per_scene", 8), ("pool_size", 24), ("test_size", 16)))
WEIGHTS = (1.0, 0.5, 0.2, 1.0, -2.0, 0.0, -0.5)


def choices(episode):
    return [turn.chosen for turn in episode.turns]


def test_the_training_condition_is_the_thesis_s_and_comes_from_the_ch7_training_suite():
    condition = training_condition()
    c = condition.condition
    assert (condition.task, c.budget, c.turns, c.change_every) == ("prepare-lunch", 15.0, 30, 10)
    assert dict(condition.costs) == {"demo": 2.0, "feature": 2.0, "label": 1.0, "none": 0.0}
    assert condition.data_seed != 0  # never the ch7 suite's data
    default = training_condition("no/such/suite.toml")
    assert default.condition == c and default.data_seed == 100 and "built-in" in default.source


def test_training_and_validation_seeds_never_meet_nor_touch_the_ch7_seeds():
    train = {training_seed(i, k, 8) for i in range(1, 101) for k in range(8)}
    held_out = set(validation_seeds(10))
    assert len(train) == 800 and min(train) == TRAIN_SEED_BASE and not train & held_out
    assert min(held_out) == VALIDATION_SEED_BASE and not (train | held_out) & set(range(5))
    with pytest.raises(SettingsError, match="validation episodes must be a whole number in 1..500"):
        validation_seeds(501)


def test_a_rollout_is_deterministic_by_seed_and_records_every_turn():
    task = RolloutTask(SMALL.spec(TRAIN_SEED_BASE), WEIGHTS, (0, 1, 0))
    episode, accuracy = play(task)
    again, accuracy_again = play(task)
    assert len(episode.turns) == 8 and episode.feature_names == FEATURE_NAMES
    assert choices(episode) == choices(again) and accuracy == accuracy_again
    assert all(np.array_equal(a.phi, b.phi) for a, b in zip(episode.turns, again.turns))
    other_policy, _ = play(replace(task, policy_seed=(1, 1, 0)))
    assert choices(other_policy) != choices(episode)  # the MaxEnt policy samples: its own seed matters
    assert episode.turns[0].kinds[-1] == "none" and episode.metadata["seed"] == TRAIN_SEED_BASE
    greedy, greedy_accuracy = play(RolloutTask(SMALL.spec(VALIDATION_SEED_BASE), WEIGHTS))
    assert greedy is None and 0.0 <= greedy_accuracy <= 1.0


def test_rollouts_on_two_workers_equal_those_played_here():
    here = RolloutPool(workers=1)
    with RolloutPool(workers=2) as pool:
        rollouts, evaluate = rollout_functions(SMALL, pool, seed=3, n_validation=2)
        parallel = rollouts(np.array(WEIGHTS), 2, 3)
        parallel_score = evaluate(np.array(WEIGHTS))
    serial_rollouts, serial_evaluate = rollout_functions(SMALL, here, seed=3, n_validation=2)
    serial = serial_rollouts(np.array(WEIGHTS), 2, 3)
    assert [choices(e) for e in parallel] == [choices(e) for e in serial]
    assert [e.metadata["seed"] for e in serial] == [training_seed(2, k, 3) for k in range(3)]
    assert parallel_score == serial_evaluate(np.array(WEIGHTS))


def test_ray_absent_or_bad_worker_counts_get_one_line(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    with pytest.raises(Exception, match=r"--ray needs the optional extra: pip install 'teachbot\[ray\]'"):
        RolloutPool(ray_address="local").__enter__()
    with pytest.raises(SettingsError, match="workers must be a whole number >= 1"):
        RolloutPool(workers=0)


@pytest.mark.e2e
def test_learn_weights_by_trajectory_on_the_real_loop_writes_weights_with_provenance(tmp_path, capsys):
    out = tmp_path / "w.toml"
    assert main(["learn-weights", "--demos", "shipped", "--out", str(out), "--method", "trajectory",
                 "--iterations", "2", "--rollouts", "2",
                 "--validation-episodes", "2", "--evaluate-every", "1", "--workers", "2", "--no-check", "--json"]) == 0
    printed = capsys.readouterr().out
    assert "iteration   2/2" in printed and "total" in printed and "validation accuracy" in printed
    weights = load_weights(out, EXTENDED_FEATURE_NAMES)  # the shipped demonstrations record the habits too
    p = weights.provenance
    assert p["method"] == "maxent-irl-trajectory" and p["iterations"] == 2 and 0 <= p["best_iteration"] <= 2
    assert p["data_seed"] == training_condition().data_seed and p["budget"] == 15.0 and p["turns"] == 30
    assert p["validation_seeds"] == "500-501" and p["training_rollout_seeds"] == "1000-1003"
    assert len(p["train_episodes"].split(", ")) == 3 and p["held_out_turns"] > 0
    assert 0 <= p["validation_accuracy"] <= 1 and 0 <= p["held_out_agreement"] <= 1
    assert p["held_out_log_likelihood"] < 0 and p["demonstrations"].endswith(".json")
    assert p["commit"] == "unknown" or len(p["commit"]) == 40
    assert "selection" not in p and "validation seeds" in p["select_by"]
    assert p["start"].startswith("per-turn MaxEnt fit")  # the default since issue 15 (the shipped file: w = 0)


def test_options_of_the_other_method_are_refused(tmp_path, capsys):
    out = str(tmp_path / "w.toml")
    assert main(["learn-weights", "--demos", "shipped", "--out", out, "--method", "trajectory", "--policy",
                 "softmax"]) == 2
    assert "--policy do(es) not apply to --method trajectory" in capsys.readouterr().err
    assert main(["learn-weights", "--demos", "shipped", "--out", out, "--workers", "2"]) == 2
    assert "--workers do(es) not apply to --method imitation" in capsys.readouterr().err  # the default method
    assert main(["learn-weights", "--demos", "shipped", "--out", out, "--method", "per-turn", "--ray", "local"]) == 2
    assert "--ray do(es) not apply to --method per-turn" in capsys.readouterr().err
    assert main(["learn-weights", "--demos", "shipped", "--out", out, "--method", "per-turn", "--start", "zero"]) == 2
    assert "--start do(es) not apply to --method per-turn" in capsys.readouterr().err
    assert main(["learn-weights", "--demos", "shipped", "--out", out, "--method", "trajectory",
                 "--train-episodes", "999"]) == 2
    assert "--train-episodes must be in 1.." in capsys.readouterr().err  # before any rollout is played
