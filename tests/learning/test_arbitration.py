"""All nine strategies in the teaching loop (thesis ch. 6-7), on a simulator-free task."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning.actions import DemoQuery, FeatureQuery, NoQuery
from learning.decision.candidates import expected_decision_features
from learning.decision.features import FEATURE_NAMES
from learning.decision.resolution import EU_RESOLUTION
from learning.decision.weights import PRESETS, load_weight_file, preset_weights, resolve_weights
from learning.strategies import STRATEGY_NAMES, DecisionTheoreticStrategy, make_strategy
from learning.strategies.decision_theoretic import choose_index
from learning.synthetic import SyntheticTask, random_state, run_episode

TASK = SyntheticTask(n_features=10, n_informative=3, seed=1)


def test_every_strategy_name_is_registered():
    assert STRATEGY_NAMES == ("passive", "active", "random", "hfs-passive", "hfs-active", "all-cd", "dt", "dt-iros",
                              "dt-task", "dt-iros-v1", "dt-task-v1", "dt-task-env", "dt-task-env-v1",
                              "dt-task-env-thesis", "dt-task-env-no-env", "dt-task-habits",
                              "scripted-expert", "passive-fs", "active-fs", "dt-voi")
    for name in STRATEGY_NAMES:
        assert make_strategy(name).name == name


@settings(max_examples=20, deadline=None)
@given(st.sampled_from(STRATEGY_NAMES), st.integers(0, 12), st.integers(0, 1000),
       st.sampled_from([{"label": 1, "demo": 2, "feature": 2, "none": 0}, {"label": 3, "demo": 1, "feature": 5,
                                                                           "none": 0}]))
def test_no_strategy_exceeds_the_budget_or_repeats_the_feature_query(name, budget, seed, costs):
    summary = run_episode(make_strategy(name), TASK, np.random.default_rng(seed), budget=budget, turns=8,
                          change_every=3, objects=4, costs=costs, test_objects=20)
    assert summary.spent <= budget
    assert sum(a.kind == "feature" for a in summary.actions) <= 1
    assert all(isinstance(e, str) and e.endswith(".") for e in summary.explanations)


def test_rule_based_strategies_ask_for_features_first():
    for name in ("hfs-passive", "hfs-active", "all-cd"):
        summary = run_episode(make_strategy(name), TASK, np.random.default_rng(0), budget=30, turns=12, objects=12)
        assert summary.actions[0] == FeatureQuery()
        later = {a.kind for a in summary.actions[1:] if a.kind != "none"}
        assert later == {"hfs-passive": {"demo"}, "hfs-active": {"label"}, "all-cd": {"demo", "label"}}[name]


def test_all_cd_asks_a_minimal_balanced_set_of_demonstrations_then_labels():
    summary = run_episode(make_strategy("all-cd"), TASK, np.random.default_rng(1), budget=60, turns=14, objects=40)
    kinds = [a.kind for a in summary.actions]
    assert kinds[:9] == ["feature"] + ["demo"] * 8 and set(kinds[9:]) == {"label"}
    demos = [a.concept for a in summary.actions if a.kind == "demo"]
    assert sorted(demos) == sorted(TASK.concepts * 2)


def test_a_concept_missing_from_the_scene_is_not_asked_for_again():
    state = random_state(TASK, 0, 4, np.random.default_rng(9))
    missing = TASK.concepts[0]
    assert state.apply(DemoQuery(missing), None).kind == "absent"  # the teacher showed nothing
    assert missing in state.absent_in_scene
    for name in ("passive", "all-cd"):
        assert make_strategy(name).choose(state, np.random.default_rng(0)).action != DemoQuery(missing)
    assert DemoQuery(missing) not in expected_decision_features(state).actions


def test_random_mixes_query_types_and_never_stays_quiet_with_budget():
    summary = run_episode(make_strategy("random"), TASK, np.random.default_rng(2), budget=100, turns=30, objects=6)
    kinds = [a.kind for a in summary.actions]
    assert {"label", "demo", "feature"} <= set(kinds) and "none" not in kinds


def test_strategies_learn_the_task():
    # DT with fixed hand-set weights: the learned dt-task-env weights are being re-learned (issue 15).
    accuracies = {name: run_episode(make_strategy(name), TASK, np.random.default_rng(3), budget=25, turns=20,
                                    change_every=5, objects=8).accuracy for name in ("all-cd", "dt-task")}
    assert min(accuracies.values()) > 0.6, accuracies  # chance is 0.25


def test_dt_stays_quiet_when_no_query_beats_the_current_state():
    state = random_state(TASK, 6, 4, np.random.default_rng(4))
    quiet = DecisionTheoreticStrategy({"budget_consumption": -1.0}).choose(state, np.random.default_rng(0))
    assert quiet.action == NoQuery()
    assert quiet.explanation == ("Nothing to ask: asking now would spend question budget I would rather keep, and no "
                                 "question promises anything to make up for it.")
    assert dict(quiet.terms)["budget_consumption"] < 0
    state.place_progress(last_query_scene_id=state.scene_id)
    assert "the scene hasn't changed since my last question" in (
        DecisionTheoreticStrategy({"budget_consumption": -1.0}).choose(state, np.random.default_rng(0)).explanation)
    eager = DecisionTheoreticStrategy({"classifier_discriminability": 1.0})
    decision = eager.choose(state, np.random.default_rng(0))
    assert decision.action.kind in ("demo", "label") and "I expect to learn the most about" in decision.explanation


def test_dt_takes_the_argmax_and_breaks_ties_towards_no_query():
    assert choose_index(np.array([0.2, 0.5, 0.4, 0.3])) == 1
    assert choose_index(np.array([0.2, 0.5, 0.5])) == 2  # a query must beat U(s), not tie it
    assert choose_index(np.array([0.7])) == 0


def test_dt_treats_expected_utilities_closer_than_its_resolution_as_equal():
    """Rounding (e.g. a single- instead of a double-precision factor, ~1e-8) decides no tie: of two queries within
    EU_RESOLUTION the first in candidate order is asked, and a query that beats no query only by rounding is not."""
    below = 0.2 * EU_RESOLUTION
    assert choose_index(np.array([0.213, 0.213 + below, 0.1])) == 0
    assert choose_index(np.array([0.213, 0.213 + 5 * EU_RESOLUTION, 0.1])) == 1  # a real difference still counts
    assert choose_index(np.array([0.3, 0.3 - below])) == 1  # no query, not a rounding-level gain
    assert choose_index(np.array([0.3 + 5 * EU_RESOLUTION, 0.3])) == 0
    assert choose_index(np.array([-40.0, -40.0 + 20 * below, -41.0])) == 0  # relative to |EU| when it exceeds 1


def test_dt_chooses_what_its_expected_features_say():
    state = random_state(TASK, 10, 5, np.random.default_rng(5))
    strategy = make_strategy("dt-task-env-v1")
    decision = strategy.choose(state, np.random.default_rng(0))
    candidates = expected_decision_features(state, habits=True)  # dt-task-env-v1 weighs the expert-habit features too
    expected_choice = candidates.actions[choose_index(candidates.utilities(preset_weights("dt-task-env-v1")))]
    assert decision.action == expected_choice
    np.testing.assert_allclose(strategy.last_candidates.expected, candidates.expected)


def test_dt_with_the_reference_engine_agrees_with_the_fast_engine():
    for seed in range(3):
        state = random_state(TASK, 8, 4, np.random.default_rng(seed))
        fast = make_strategy("dt-task").choose(state, np.random.default_rng(0)).action
        reference = make_strategy("dt-task", engine="reference").choose(state, np.random.default_rng(0)).action
        assert fast == reference


def test_dt_asks_a_costly_query_only_when_it_pays():
    state = random_state(TASK, 2, 6, np.random.default_rng(6), budget=10)
    candidates = expected_decision_features(state)
    free = dict(zip(FEATURE_NAMES, preset_weights("dt-task")))
    priced = {**free, "budget_consumption": -100.0}
    assert make_strategy("dt", weights=priced).choose(state, np.random.default_rng(0)).action == NoQuery()
    assert candidates.utilities(resolve_weights(free)).argmax() != len(candidates.actions) - 1


def test_weight_presets_load_and_bad_weights_are_explained(tmp_path):
    from learning.decision.habits import EXTENDED_FEATURE_NAMES

    for name in PRESETS:
        weights = preset_weights(name)
        assert weights.shape in ((len(FEATURE_NAMES),), (len(EXTENDED_FEATURE_NAMES),)) and np.all(np.isfinite(weights))
    assert preset_weights("dt-task-env-v1").shape == (len(EXTENDED_FEATURE_NAMES),)
    assert preset_weights("dt-task-env-thesis").shape == (len(FEATURE_NAMES),)  # the thesis's seven, unchanged
    assert np.count_nonzero(preset_weights("dt-iros")[2:]) == 0
    assert np.count_nonzero(preset_weights("dt-task")[4:]) == 0
    np.testing.assert_allclose(resolve_weights({"instance_variation": 2.0}), [0, 0, 2, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="unknown decision feature 'curiosity'"):
        resolve_weights({"curiosity": 1.0})
    with pytest.raises(ValueError, match="expected 7 weights"):
        resolve_weights([1.0, 2.0])
    with pytest.raises(ValueError, match="must be a finite real number"):
        resolve_weights({"prediction_margin": float("nan")})
    bad = tmp_path / "bad.toml"
    bad.write_text("[weights]\nprediction_margin = 'high'\n")
    with pytest.raises(ValueError, match="bad.toml: weight 'prediction_margin' must be a finite number"):
        load_weight_file(bad)
    bad.write_text("weights = 3\n")
    with pytest.raises(ValueError, match=r"needs a non-empty \[weights\] table"):
        load_weight_file(bad)
    bad.write_text("[weights\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_weight_file(bad)
    with pytest.raises(ValueError, match="does not exist"):
        load_weight_file(tmp_path / "missing.toml")
    good = tmp_path / "mine.toml"
    good.write_text("# my weights\n[weights]\nclassifier_discriminability = 2.0\n\n[provenance]\nmethod = 'hand'\n")
    strategy = make_strategy("dt", weights=str(good))
    assert strategy.name == "dt" and strategy.weights[0] == 2.0


def test_make_strategy_rejects_unknown_names_and_options():
    with pytest.raises(ValueError, match="choose one of: passive, active, random"):
        make_strategy("clever")
    with pytest.raises(ValueError, match="does not take the options"):
        make_strategy("passive", weights={})
    assert make_strategy("all-cd", examples_per_concept=1).examples_per_concept == 1


def test_passive_and_demo_candidates_need_a_scene():
    state = random_state(TASK, 3, 0, np.random.default_rng(7))
    assert all(not isinstance(a, DemoQuery) for a in expected_decision_features(state).actions)
