"""Issue 39's plan for the thesis's DT-task-env: the committed plan is well-formed and its sign constraints reach
every fit of the protocol (learning/irl/fit-plan-dt-task-env.toml, docs/irl.md)."""

from pathlib import Path

import numpy as np

from dialog.experiments.suite import load_suite
from learning.datafiles import read_toml
from learning.decision.features import FEATURE_NAMES, LEARNING_FEATURES

ROOT = Path(__file__).resolve().parents[2]
PLAN = read_toml(ROOT / "learning" / "irl" / "fit-plan-dt-task-env.toml", "plan")


def test_the_plan_gives_the_thesiss_roles_as_signs():
    signs = PLAN["signs"]
    assert set(signs) <= set(FEATURE_NAMES) and "remaining_time" not in signs  # unidentified: no sign
    assert all(signs[name] == 1 for name in LEARNING_FEATURES)
    assert signs["budget_consumption"] == -1 and signs["non_query_time"] == -1
    assert PLAN["fit"]["features"] == "thesis" and PLAN["fit"]["demos"] == "shipped"


def test_the_prediction_names_a_suite_that_runs_it():
    prediction = PLAN["prediction"]
    suite = load_suite(ROOT / prediction["suite"])
    conditions = {c.name: c for c in suite.conditions}
    liberal, thrifty = conditions[prediction["liberal_condition"]], conditions[prediction["thrifty_condition"]]
    assert (liberal.budget, liberal.turns) == (500, 150) and (thrifty.budget, thrifty.turns) == (25, 150)
    assert {"dt-task-env", prediction["compare_with"]} <= set(suite.strategies)
    assert suite.data_seed >= 100  # calibration data: no reported table uses it


def test_every_fit_of_the_protocol_keeps_the_signs():
    """A known expert that dislikes spending, fitted with the plan's signs: every fit (both forms, every split
    and start) has its learning weights >= 0 and its budget and idle weights <= 0, and still imitates."""
    from learning.irl.imitation import fit_protocol, shipped_fit
    from tests.learning.test_irl import TRUE_WEIGHTS, demonstrations, greedy_policy

    episodes = demonstrations(greedy_policy(TRUE_WEIGHTS), np.random.default_rng(7), 15)
    signs = tuple((name, int(sign)) for name, sign in PLAN["signs"].items())
    fits = fit_protocol(episodes, split_seeds=[0], fit_seeds=[0, 1], signs=signs)
    for fit in fits:
        w = fit.weights.as_dict()
        assert all(w[name] >= 0 for name, sign in signs if sign > 0), w
        assert all(w[name] <= 0 for name, sign in signs if sign < 0), w
    assert shipped_fit(fits).held_out_scores["exact_agreement"] >= 0.8


def test_the_shipped_dt_task_env_is_the_plans_fit():
    """dt-task-env weighs the seven features with the plan's signs and says where it came from."""
    from learning.decision.weights import WEIGHTS_DIRECTORY
    from learning.decision.weights_file import load_weights

    shipped = load_weights(WEIGHTS_DIRECTORY / "dt-task-env.toml")
    assert shipped.feature_names == FEATURE_NAMES
    w = shipped.as_dict()
    for name, sign in PLAN["signs"].items():
        assert w[name] * sign >= 0, (name, w[name])
    assert w["budget_consumption"] < 0  # the prediction's part (a): a cost on spending, not at its bound
    assert shipped.provenance["plan"] == "learning/irl/fit-plan-dt-task-env.toml"
    assert "budget_consumption <= 0" in shipped.provenance["signs"]
