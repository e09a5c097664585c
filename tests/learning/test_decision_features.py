"""Decision features of thesis ch. 6-7: hand computations and the [0, 1] range."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from learning.actions import DemoQuery, NoQuery
from learning.decision.features import (
    FEATURE_NAMES,
    Clock,
    class_uniformity,
    discriminability,
    features,
    instance_variation,
    prediction_margin,
    state_clock,
    state_features,
    window_turns,
)
from learning.synthetic import SyntheticTask, random_state

P = np.array([[0.9, 0.2], [0.5, 0.4], [0.1, 0.6]])  # 3 objects x 2 concepts


def test_discriminability_is_the_mean_range_per_concept():
    assert discriminability(P) == pytest.approx(((0.9 - 0.1) + (0.6 - 0.2)) / 2)


def test_class_uniformity_is_smallest_over_largest_count():
    assert class_uniformity(np.array([2, 4, 3])) == pytest.approx(0.5)
    assert class_uniformity(np.array([3, 3])) == 1.0
    assert class_uniformity(np.array([0, 0, 0])) == 0.0  # no examples: no distribution yet
    assert class_uniformity(np.array([0, 5])) == 0.0


def test_instance_variation_is_the_scaled_coefficient_of_variation():
    column = P[:, 0]
    expected = (column.std() / column.mean() + P[:, 1].std() / P[:, 1].mean()) / 2 / np.sqrt(2)
    assert instance_variation(P) == pytest.approx(expected)
    one_hot = np.array([[1.0], [0.0], [0.0], [0.0]])  # all mass on one object: the maximum
    assert instance_variation(one_hot) == pytest.approx(1.0)
    assert instance_variation(np.full((4, 2), 0.3)) == 0.0
    assert instance_variation(P[:1]) == 0.0  # one object: no variation


def test_prediction_margin_uses_labels_normalised_over_concepts():
    rows = P / P.sum(axis=1, keepdims=True)
    expected = np.mean(np.abs(rows[:, 0] - rows[:, 1]))
    assert prediction_margin(P) == pytest.approx(expected)
    assert prediction_margin(np.array([[0.7, 0.7, 0.1]])) == pytest.approx(0.0)  # a tie on top


def test_features_batch_over_leading_axes():
    batch = np.stack([P, P[::-1], 1 - P])
    phi = features(batch, np.array([1, 2]), Clock(3, 10, 4, 20, 2, 5))
    assert phi.shape == (3, len(FEATURE_NAMES))
    np.testing.assert_allclose(phi[1], features(P[::-1], np.array([1, 2]), Clock(3, 10, 4, 20, 2, 5)))
    np.testing.assert_allclose(phi[0, 4:], [0.3, 0.8, 0.4])


def test_clock_after_a_query_and_after_silence():
    clock = Clock(spent=4, budget=10, turn=5, turns=20, quiet_run=3, window=5)
    asked = clock.after(2, asked=True)
    assert (asked.budget_consumption(), asked.remaining_time(), asked.non_query_time()) == (0.6, 0.7, 0.0)
    quiet = clock.after(0, asked=False).after(0, asked=False).after(0, asked=False)
    assert quiet.non_query_time() == 1.0 and quiet.budget_consumption() == 0.4
    assert Clock(0, 0, 0, 1, 0, 1).budget_consumption() == 1.0  # no budget counts as spent


def test_window_is_proportional_to_the_change_rate():
    assert window_turns(10) == 10 and window_turns(1) == 1 and window_turns(5, 0.5) == 2
    with pytest.raises(ValueError, match="window_factor must be a positive number"):
        window_turns(5, 0.0)


@settings(max_examples=80, deadline=None)
@given(
    arrays(np.float64, st.tuples(st.integers(0, 3), st.integers(0, 7), st.integers(1, 5)),
           elements=st.floats(0.0, 1.0)),
    st.lists(st.integers(0, 30), min_size=5, max_size=5),
    st.floats(0, 50), st.floats(0, 50), st.integers(0, 60), st.integers(1, 60), st.integers(0, 80),
    st.integers(1, 20),
)
def test_every_feature_stays_in_the_unit_interval(P, counts, spent, budget, turn, turns, quiet, window):
    counts = np.array(counts[: P.shape[-1]])
    clock = Clock(min(spent, budget), budget, turn, turns, quiet, window)
    phi = features(P, counts, clock)
    assert phi.shape == P.shape[:-2] + (len(FEATURE_NAMES),)
    assert np.all(np.isfinite(phi)) and np.all(phi >= 0.0) and np.all(phi <= 1.0)


def test_state_features_read_the_learning_state():
    task = SyntheticTask(n_features=8, n_informative=3)
    state = random_state(task, 12, 6, np.random.default_rng(0), budget=20, turns=40)
    state.place_progress(history=["label", "none", "none"])
    phi = state_features(state)
    assert np.all((phi >= 0) & (phi <= 1))
    clock = state_clock(state)
    assert clock.quiet_run == 2 and clock.window == state.change_every
    assert phi[FEATURE_NAMES.index("non_query_time")] == pytest.approx(2 / state.change_every)
    state.apply(DemoQuery(task.concepts[0]), None)
    state.apply(NoQuery())
    assert state.quiet_run() == 1
