"""Embodied query costs on the learning side (thesis §8.2.2): remaining time in seconds, DT's gain per second."""

import numpy as np
import pytest

from learning.actions import LabelQuery, NoQuery
from learning.decision.candidates import expected_decision_features
from learning.decision.embodied import SecondsClock, choose_per_second
from learning.decision.features import FEATURE_NAMES
from learning.strategies import make_strategy
from learning.synthetic import SyntheticTask, random_state

TASK = SyntheticTask(seed=3)
TURN_SECONDS = {"label": 9.0, "demo": 16.0, "feature": 36.0, "none": 2.0}
TIME = FEATURE_NAMES.index("remaining_time")


def embodied_state(pointing, elapsed=30.0, allocation=300.0, seed=0):
    state = random_state(TASK, 20, len(pointing), np.random.default_rng(seed))
    state.set_seconds_clock(SecondsClock(allocation, elapsed, TURN_SECONDS, np.asarray(pointing, dtype=float)))
    return state


def test_a_far_objects_label_query_costs_more_seconds_and_leaves_less_time():
    state = embodied_state([2.6, 4.2, 3.0, 2.8])  # object 1 is the far one
    c = expected_decision_features(state)
    rows = {a.object_index: i for i, a in enumerate(c.actions) if a.kind == "label"}
    far, near = rows[1], rows[0]
    assert c.seconds[far] == pytest.approx(9.0 + 4.2) and c.seconds[near] == pytest.approx(9.0 + 2.6)
    assert c.expected[far, TIME] < c.expected[near, TIME]
    assert c.expected[near, TIME] == pytest.approx((300 - 30 - 11.6) / 300)
    assert c.expected[c.no_query_index, TIME] == pytest.approx((300 - 30 - 2.0) / 300)  # a quiet turn's 2 s


def test_without_a_seconds_clock_time_reads_turns_and_nothing_changes():
    state = embodied_state([2.6, 4.2, 3.0, 2.8])
    with_seconds = expected_decision_features(state)
    ignoring = expected_decision_features(state, seconds=False)
    state.set_seconds_clock(None)
    plain = expected_decision_features(state)
    assert plain.seconds is None and ignoring.seconds is None
    np.testing.assert_array_equal(plain.expected, ignoring.expected)
    np.testing.assert_array_equal(plain.expected[:, :TIME], with_seconds.expected[:, :TIME])  # learning unchanged
    assert np.ptp(plain.expected[:, TIME]) == 0  # turns: every row shares the next turn's time


def test_the_rule_takes_the_largest_gain_per_second_among_queries_that_beat_no_query():
    utilities = np.array([0.50, 0.50, 0.90, 0.30])  # two tied labels, a slow better query, no query last
    assert choose_per_second(utilities, np.array([13.0, 11.0, 40.0, 2.0]), 1e-12) == 1  # 0.2/11 > 0.6/40
    assert choose_per_second(utilities, np.array([13.0, 11.0, 20.0, 2.0]), 1e-12) == 2  # 0.6/20 > 0.2/11
    assert choose_per_second(np.array([0.2, 0.1, 0.3]), np.array([5.0, 5.0, 2.0]), 1e-12) == 2  # none beats quiet
    rounding = np.array([0.50, 0.50 + 1e-9, 0.30])  # equal gains up to rounding, equal seconds: the first
    assert choose_per_second(rounding, np.array([10.0, 10.0, 2.0]), 1e-6) == 0
    assert choose_per_second(rounding, np.array([10.0, 9.0, 2.0]), 1e-6) == 1  # a real rate difference counts


def test_dt_prefers_the_near_object_when_gains_tie():
    state = random_state(TASK, 20, 1, np.random.default_rng(1), budget=3.0)
    row = state.scene_X[0]
    state.observe_scene(7, np.vstack([row, row]))  # two identical objects: their label queries tie
    state.place_progress(spent=2.0)  # one unit left: only label queries are affordable
    turns = make_strategy("dt-iros").choose(state, np.random.default_rng(0)).action
    state.set_seconds_clock(SecondsClock(300.0, 0.0, TURN_SECONDS, np.array([4.0, 2.5])))  # object 0 is far
    seconds = make_strategy("dt-iros").choose(state, np.random.default_rng(0)).action
    if turns == NoQuery():
        pytest.skip("no label query beats staying quiet in this state")
    assert turns == LabelQuery(0)  # in turns, ties go to the first
    assert seconds == LabelQuery(1)  # in seconds, the near one


def test_a_seconds_clock_refuses_nonsense():
    with pytest.raises(ValueError, match="positive"):
        SecondsClock(0.0, 0.0, TURN_SECONDS)
    with pytest.raises(ValueError, match="every kind"):
        SecondsClock(60.0, 0.0, {"label": 1.0})
    with pytest.raises(ValueError, match="pointing"):
        SecondsClock(60.0, 0.0, TURN_SECONDS, np.array([-1.0]))
