"""Learning state bookkeeping and the two baseline strategies."""

import numpy as np
import pytest

from learning.actions import DemoQuery, FeatureQuery, LabelQuery, NoQuery, validate_costs
from learning.concepts import entropy
from learning.evaluation import accuracy
from learning.state import LearningState
from learning.strategies import make_strategy

CONCEPTS = ("a", "b", "c")


def blobs(rng, per_class=6):
    centres = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0]], dtype=float)
    X = np.vstack([c + rng.normal(0, 0.5, (per_class, 3)) for c in centres])
    return X, np.repeat(CONCEPTS, per_class)


def state_with_scene(rng, budget=10, turns=10):
    state = LearningState(CONCEPTS, ["f1", "f2", "f3"], budget=budget, turns=turns)
    X, labels = blobs(rng)
    state.observe_scene(0, X)
    return state, X, labels


def test_labelled_examples_make_the_models_accurate(rng):
    state, X, labels = state_with_scene(rng)
    for index in range(0, len(X), 2):
        state.apply(LabelQuery(index), labels[index])
    X_test, y_test = blobs(rng, 20)
    assert accuracy(state.predict(X_test), y_test) > 0.9


def test_budget_is_charged_and_never_exceeded(rng):
    state, _, _ = state_with_scene(rng, budget=3)
    state.apply(DemoQuery("a"), None)
    assert state.remaining_budget == 1 and state.can_afford(LabelQuery(0))
    assert not state.can_afford(DemoQuery("b"))
    with pytest.raises(ValueError, match="costs 2"):
        state.apply(DemoQuery("b"), 0)
    state.apply(NoQuery())
    assert state.spent == 2 and state.history == ("demo", "none") and len(state.examples) == 0


def test_passive_asks_for_the_least_represented_concept(rng):
    state, X, labels = state_with_scene(rng)
    state.apply(DemoQuery("a"), 0)
    state.apply(DemoQuery("b"), 7)
    decision = make_strategy("passive").choose(state, rng)
    assert decision.action == DemoQuery("c")


def test_active_asks_about_the_most_uncertain_object(rng):
    state, X, labels = state_with_scene(rng)
    state.apply(LabelQuery(0), "a")
    state.apply(LabelQuery(6), "b")
    decision = make_strategy("active").choose(state, rng)
    scores = entropy(state.probabilities())
    assert decision.action == LabelQuery(int(np.argmax(scores)))
    assert "can't tell" in decision.explanation


def test_active_does_not_repeat_an_object_in_the_same_scene(rng):
    state, X, _ = state_with_scene(rng, budget=100, turns=100)
    strategy, asked = make_strategy("active"), set()
    for _ in range(len(X)):
        action = strategy.choose(state, rng).action
        assert action.object_index not in asked
        asked.add(action.object_index)
        state.apply(action, None)
    assert strategy.choose(state, rng).action == NoQuery()


def test_strategies_stay_quiet_without_budget(rng):
    state, _, _ = state_with_scene(rng, budget=0)
    for name in ("passive", "active"):
        decision = make_strategy(name).choose(state, rng)
        assert decision.action == NoQuery() and "budget" in decision.explanation


def test_unknown_strategy_and_bad_costs_are_clear_errors():
    with pytest.raises(ValueError, match="choose one of: passive, active"):
        make_strategy("clever")
    with pytest.raises(ValueError, match="missing"):
        validate_costs({"label": 1})
    with pytest.raises(ValueError, match="non-negative"):
        validate_costs({"label": -1, "demo": 2, "feature": 2, "none": 0})


def test_undo_removes_the_last_example(rng):
    state, X, _ = state_with_scene(rng)
    state.apply(LabelQuery(0), "a")
    before = state.probabilities().copy()
    change = state.apply(LabelQuery(1), "b")
    state.undo(change)
    assert change.concept == "b" and [e.concept for e in state.examples] == ["a"]
    assert np.allclose(state.probabilities(), before) and state.turn == 2  # the turn stays over
    assert state.spent == 1  # the taken-back label's budget is given back


def test_the_thesis_baselines_select_features_computationally(rng):
    """Issue 26 item 2: P and A of figs. 6.4-6.5 'use computational feature selection'; passive/active use all."""
    from learning.features.selection import computational_subsets
    from learning.strategies import make_strategy as make
    X, labels = blobs(rng)
    noisy = np.hstack([X, rng.normal(size=(len(X), 6))])  # six features that say nothing about the concepts
    names = ["f1", "f2", "f3", *(f"noise{i}" for i in range(6))]
    plain = LearningState(CONCEPTS, names, budget=50, turns=50)
    selecting = LearningState(CONCEPTS, names, budget=50, turns=50, feature_selection="ES")
    for state in (plain, selecting):
        state.observe_scene(0, noisy)
        for i in range(12):
            state.apply(LabelQuery(i), labels[i])
    X_train, y_train = selecting.training_matrix()
    expected = computational_subsets(X_train, y_train, CONCEPTS, method="ES")
    fitted = selecting._models.subsets_
    assert all(np.array_equal(fitted[c], expected[c]) for c in CONCEPTS if c in expected)
    assert all(plain._models.subsets_[c] is None for c in CONCEPTS)
    assert not np.allclose(plain.probabilities(), selecting.probabilities())
    selecting.apply(FeatureQuery(), [0, 1])  # the teacher's answer, where given, wins
    assert all(selecting._models.subsets_[c].tolist() == [0, 1] for c in CONCEPTS)
    with pytest.raises(ValueError, match="feature_selection must be None or one of FI, ES, ER"):
        LearningState(CONCEPTS, names, budget=5, turns=5, feature_selection="es")
    assert make("passive-fs").feature_selection == make("active-fs").feature_selection == "ES"
    assert make("passive").feature_selection is None and make("active").feature_selection is None
