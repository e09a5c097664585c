"""Candidate actions and their expected decision features (thesis eq. 6.3, 7.1)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning.actions import DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.decision.candidates import candidate_actions, expected_decision_features
from learning.decision.features import FEATURE_NAMES, state_features
from learning.synthetic import SyntheticTask, random_state

TASK = SyntheticTask(n_features=6, n_informative=2, seed=5)
BUDGET = FEATURE_NAMES.index("budget_consumption")
TIME = FEATURE_NAMES.index("remaining_time")
QUIET = FEATURE_NAMES.index("non_query_time")
CDU = FEATURE_NAMES.index("class_distribution_uniformity")


def small_state(seed=0, **kwargs):
    kwargs.setdefault("budget", 20.0)
    kwargs.setdefault("turns", 40)
    return random_state(TASK, kwargs.pop("n_train", 6), kwargs.pop("n_objects", 4), np.random.default_rng(seed),
                        **kwargs)


def test_candidates_come_in_a_fixed_order_with_no_query_last():
    state = small_state()
    state.apply(LabelQuery(1), None)  # asked about object 1 (the teacher skipped)
    actions = candidate_actions(state)
    assert actions == (*(DemoQuery(c) for c in TASK.concepts), LabelQuery(0), LabelQuery(2), LabelQuery(3),
                       FeatureQuery(), NoQuery())


def test_a_demonstrated_object_is_not_asked_about_again():
    state = small_state()
    change = state.apply(DemoQuery(TASK.concepts[1]), 2)
    assert LabelQuery(2) not in candidate_actions(state)
    state.undo(change)
    assert LabelQuery(2) in candidate_actions(state)


def test_only_affordable_queries_are_candidates():
    state = small_state()
    state.place_progress(spent=state.budget - 1)  # one unit left: label queries only
    assert {a.kind for a in candidate_actions(state)} == {"label", "none"}
    state.place_progress(spent=state.budget)
    assert candidate_actions(state) == (NoQuery(),)


def test_expected_features_follow_each_query_into_the_next_turn():
    state = small_state(1)
    state.place_progress(history=["none", "none"])
    candidates = expected_decision_features(state)
    current = state_features(state)
    np.testing.assert_allclose(candidates.current, current)
    quiet = candidates.expected[-1]  # no query is scored at s_{t+1} too (eq. 7.1): the clock moves on
    np.testing.assert_allclose(quiet[:BUDGET], current[:BUDGET])  # nothing learned by staying quiet
    assert quiet[BUDGET] == pytest.approx(state.spent / state.budget)
    assert quiet[TIME] == pytest.approx((state.turns - state.turn - 1) / state.turns)
    window = state.change_every
    assert quiet[QUIET] == pytest.approx(min(3, window) / window)  # two quiet turns so far, and this one
    for action, row in zip(candidates.actions[:-1], candidates.expected[:-1]):
        assert row[BUDGET] == pytest.approx((state.spent + state.cost(action)) / state.budget)
        assert row[TIME] == pytest.approx((state.turns - state.turn - 1) / state.turns)
        assert row[QUIET] == 0.0
    utilities = candidates.utilities(np.eye(len(FEATURE_NAMES))[BUDGET])
    assert utilities[candidates.no_query_index] == pytest.approx(current[BUDGET])


def test_class_uniformity_is_expected_over_the_answers():
    state = small_state(2, n_train=0)
    state.apply(LabelQuery(0), TASK.concepts[0])
    candidates = expected_decision_features(state)
    demo = candidates.expected[candidates.actions.index(DemoQuery(TASK.concepts[1]))]
    assert demo[CDU] == 0.0  # counts (1, 1, 0, 0): the smallest class is still empty
    assert np.all(candidates.expected[:, CDU] == 0.0)


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.0, 8.0), st.booleans())
def test_every_expected_feature_is_in_the_unit_interval(seed, budget, answered):
    state = small_state(seed, n_train=seed % 9, budget=budget, feature_query_answered=answered)
    state.place_progress(spent=min(state.spent, budget))
    candidates = expected_decision_features(state)
    assert np.all(candidates.expected >= 0.0) and np.all(candidates.expected <= 1.0)
    assert all(state.can_afford(action) for action in candidates.actions)
    assert (FeatureQuery() in candidates.actions) == (not answered and state.can_afford(FeatureQuery()))
