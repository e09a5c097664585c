"""What-if engines: the fast engine against the brute-force reference, and the properties both must have."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning.actions import FeatureQuery, LabelQuery
from learning.decision.candidates import candidate_actions, expected_decision_features
from learning.gp import BinaryGPClassifier, rbf_kernel
from learning.synthetic import SyntheticTask, random_state
from learning.whatif import ENGINE_NAMES, make_engine
from learning.whatif.laplace import (
    fit_modes,
    fit_weight_space,
    one_site_probabilities,
    pivoted_cholesky,
    predict_from_modes,
    predict_weight_space,
    scene_posterior,
)

TASK = SyntheticTask(n_features=6, n_informative=2, seed=3)


def small_state(seed, n_train=8, n_objects=5, answered=False, task=TASK):
    return random_state(task, n_train, n_objects, np.random.default_rng(seed), feature_query_answered=answered)


@pytest.mark.parametrize("answered", [False, True])
@pytest.mark.parametrize("n_train", [0, 1, 6, 30])
def test_fast_engine_matches_the_reference(n_train, answered):
    state = small_state(n_train, n_train=n_train, n_objects=6, answered=answered)
    fast = make_engine("fast").simulate(state, [0, 2, 5], True)
    reference = make_engine("reference").simulate(state, [0, 2, 5], True)
    assert fast.demo.shape == reference.demo.shape == (4, 6, 6, 4)
    assert fast.label.shape == reference.label.shape == (3, 4, 6, 4)
    # The one-site update keeps the old sites' precisions: close to a refit, not equal (typically ~1e-3).
    assert np.max(np.abs(fast.demo - reference.demo)) < 0.02
    assert np.max(np.abs(fast.label - reference.label)) < 0.02
    assert np.max(np.abs(fast.feature - reference.feature)) < 1e-4  # the FSQ refits are exact
    if n_train == 0:  # one site on the prior: the rank-one update is the exact Laplace fit
        np.testing.assert_allclose(fast.demo, reference.demo, atol=1e-9)


def test_expected_utilities_agree_between_engines():
    for seed in range(3):
        state = small_state(seed, n_train=12, n_objects=5)
        fast = expected_decision_features(state, "fast")
        reference = expected_decision_features(state, "reference")
        assert fast.actions == reference.actions
        assert np.max(np.abs(fast.expected - reference.expected)) < 5e-3


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(ENGINE_NAMES), st.booleans())
def test_a_demo_answer_and_a_label_answer_give_the_same_state(seed, engine, answered):
    state = small_state(seed, n_train=seed % 7, n_objects=4, answered=answered)
    outcomes = make_engine(engine).simulate(state, range(4), False)
    for x in range(4):
        for y in range(4):  # DQ(y) answered with object x == LQ(x) answered with concept y
            np.testing.assert_allclose(outcomes.demo[y, x], outcomes.label[x, y], atol=1e-12)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000), st.permutations(range(5)), st.sampled_from(ENGINE_NAMES))
def test_permuting_the_scene_only_permutes_label_indices(seed, order, engine):
    state = small_state(seed, n_train=1 + seed % 9, n_objects=5)
    shuffled = small_state(seed, n_train=1 + seed % 9, n_objects=5)
    shuffled.observe_scene(1, state.scene_X[list(order)])  # both see the same rows again: the same scaling
    state.observe_scene(1, state.scene_X)
    before = expected_decision_features(state, engine)
    after = expected_decision_features(shuffled, engine)
    position = {new: old for old, new in enumerate(order)}  # shuffled object k was object order[k]
    rows_before = {a: i for i, a in enumerate(before.actions)}
    for i, action in enumerate(after.actions):
        original = LabelQuery(order[action.object_index]) if action.kind == "label" else action
        np.testing.assert_allclose(after.expected[i], before.expected[rows_before[original]], atol=1e-9)
    assert len(position) == 5


def test_one_site_update_is_exact_without_training_data():
    rng = np.random.default_rng(0)
    scene = rng.normal(size=(5, 3))
    empty = BinaryGPClassifier(length_scale=1.5).fit(np.zeros((0, 3)), np.zeros(0))
    probabilities = one_site_probabilities(scene_posterior(empty, scene))
    for j in range(5):
        for sign, label in ((0, 1), (1, 0)):
            exact = BinaryGPClassifier(length_scale=1.5).fit(scene[j : j + 1], [label]).predict_proba(scene)
            np.testing.assert_allclose(probabilities[sign, j], exact, atol=1e-8)


def test_one_site_update_is_close_to_a_refit():
    rng = np.random.default_rng(1)
    X, scene = rng.normal(size=(25, 3)), rng.normal(size=(6, 3))
    y = X[:, 0] + 0.3 * rng.normal(size=25) > 0
    model = BinaryGPClassifier(length_scale=1.7).fit(X, y)
    probabilities = one_site_probabilities(scene_posterior(model, scene))
    for j in range(6):
        exact = BinaryGPClassifier(length_scale=1.7).fit(np.vstack([X, scene[j]]), np.append(y, True))
        assert np.max(np.abs(probabilities[0, j] - exact.predict_proba(scene))) < 5e-3


def test_batched_newton_and_low_rank_fits_match_the_classifier():
    rng = np.random.default_rng(2)
    X, scene = rng.normal(size=(40, 2)), rng.normal(size=(7, 2))
    labels = np.array([X[:, 0] > 0, X[:, 1] > 0.3, X.sum(1) < 0])
    targets = np.where(labels, 1.0, -1.0)
    exact = np.array([BinaryGPClassifier(length_scale=1.4).fit(X, row).predict_proba(scene) for row in labels])
    K, K_ns = rbf_kernel(X, X, 1.4, 4.0), rbf_kernel(X, scene, 1.4, 4.0)
    sw, factors, gradient = fit_modes(K, targets, start=rng.normal(size=targets.shape))
    np.testing.assert_allclose(predict_from_modes(K_ns, 4.0, sw, factors, gradient), exact, atol=1e-5)
    Phi = pivoted_cholesky(np.vstack([X, scene]), 1.4, 4.0, 1e-8, 47)
    assert Phi is not None and Phi.shape[1] < 47
    z, C = fit_weight_space(Phi[:40], targets)
    np.testing.assert_allclose(predict_weight_space(Phi[40:], 4.0, z, C), exact, atol=1e-5)
    assert pivoted_cholesky(np.vstack([X, scene]), 1.4, 4.0, 1e-8, 5) is None  # rank 5 is not enough


def test_the_dense_refits_warm_start_changes_only_the_path_not_the_mode(monkeypatch):
    """Issue 28: from DENSE_WARM_FROM examples Newton starts at a rank-40 approximation's mode; same result."""
    from learning.whatif import fast

    assert pivoted_cholesky(np.random.default_rng(0).normal(size=(30, 3)), 1.0, 4.0, 1e-12, 4, truncate=True).shape \
        == (30, 4)
    task = SyntheticTask(n_features=12, n_informative=4, seed=5)
    state = random_state(task, 60, 7, np.random.default_rng(1))
    subsets = {c: np.arange(5 + k) for k, c in enumerate(state.concepts)}  # > 3 features: the dense path
    monkeypatch.setattr(fast, "feature_query_subsets", lambda _state: subsets)
    cold = fast.feature_outcomes(state)
    monkeypatch.setattr(fast, "DENSE_WARM_FROM", 0)
    warm = fast.feature_outcomes(state)
    assert np.max(np.abs(warm - cold)) < 1e-5


def test_the_feature_query_is_simulated_only_while_it_can_be_asked():
    state = small_state(0, answered=True)
    assert FeatureQuery() not in candidate_actions(state)
    assert make_engine("fast").simulate(state, [], False).feature is None


def test_unknown_engine_is_a_clear_error():
    with pytest.raises(ValueError, match="choose one of: fast, reference"):
        make_engine("quick")


def test_the_in_place_arithmetic_gives_the_same_bits_as_the_plain_formulas():
    """``_probit_in_place`` is ``probit_probability`` and ``gp.triangular_solve`` is scipy's solve_triangular,
    to the bit (the decision's tables, and so every transcript, rest on it)."""
    from scipy.linalg import solve_triangular

    from learning.gp import triangular_solve
    from learning.whatif.laplace import _probit_in_place, probit_probability

    rng = np.random.default_rng(3)
    mean, variance = rng.normal(size=(2, 3, 7, 7)) * 4.0, rng.normal(size=(2, 3, 7, 7)) ** 2
    variance[0, 0, 0] = -1.0  # below MIN_VARIANCE: clipped in both
    expected = probit_probability(mean, variance)
    assert np.array_equal(_probit_in_place(mean.copy(), variance.copy()), expected)
    A = rng.normal(size=(9, 9))
    factor = np.linalg.cholesky(A @ A.T + 9.0 * np.eye(9)).astype(np.float32)
    right = rng.normal(size=(9, 4)).astype(np.float32)
    for matrix in (factor, np.asfortranarray(factor)):
        for lower, trans in ((True, 0), (True, 1)):
            plain = solve_triangular(matrix, right, lower=lower, trans=trans, check_finite=False)
            assert np.array_equal(triangular_solve(matrix, right, lower, trans), plain)
    for matrix in (factor.T, np.asfortranarray(factor.T)):  # an upper factor
        assert np.array_equal(triangular_solve(matrix, right, False, 0),
                              solve_triangular(matrix, right, lower=False, check_finite=False))
