"""Work shared or reused for speed (issue 43) gives exactly the bits the recomputation would."""

import numpy as np
import pytest

from learning.actions import FeatureQuery, LabelQuery, NoQuery
from learning.concepts import ConceptModels
from learning.decision.candidates import expected_decision_features
from learning.gp import BinaryGPClassifier, rbf_kernel
from learning.state import LearningState

CONCEPTS = ("a", "b", "c")


def _rows(rng, n=30, features=5):
    return rng.normal(size=(n, features)), rng.choice(CONCEPTS, size=n).astype(object)


@pytest.mark.parametrize("subsets", [{}, {"b": np.array([0, 2])}])
def test_models_on_the_same_columns_share_kernels_and_give_each_models_own_bits(rng, subsets):
    X, labels = _rows(rng)
    models = ConceptModels(CONCEPTS).fit(X, labels, subsets)
    test = rng.normal(size=(40, X.shape[1]))
    alone = np.column_stack([models.models_[c].predict_proba(test[:, models.columns(c, X.shape[1])])
                             for c in CONCEPTS])
    assert np.array_equal(models.predict(test), alone)
    for c in CONCEPTS:  # each fit equals a fit of its own, which computes its kernel itself
        columns = models.columns(c, X.shape[1])
        own = BinaryGPClassifier().fit(X[:, columns], labels == c)
        assert np.array_equal(models.models_[c].K_, own.K_)
        assert np.array_equal(models.models_[c].f_hat_, own.f_hat_)
        assert np.array_equal(models.models_[c].predict_proba(test[:, columns]), own.predict_proba(test[:, columns]))


def test_a_kernel_of_the_wrong_size_is_refused(rng):
    X, labels = _rows(rng, 6)
    with pytest.raises(ValueError, match=r"kernel must be \(6, 6\)"):
        BinaryGPClassifier().fit(X, labels == "a", kernel=rbf_kernel(X[:4], X[:4], 1.0, 4.0))


def test_a_quiet_turn_reuses_the_scored_what_ifs_and_gets_the_same_bits(rng):
    state = LearningState(CONCEPTS, [f"f{i}" for i in range(5)], budget=20, turns=20)
    scene, labels = _rows(rng, 12)
    state.observe_scene(0, scene)
    state.apply(LabelQuery(0), labels[0])
    state.apply(LabelQuery(1), labels[1])
    first = expected_decision_features(state, "fast", habits=True)
    state.apply(NoQuery())  # nothing learned, the same scene: the cached scoring is used
    reused = expected_decision_features(state, "fast", habits=True)
    state.cache.clear()
    fresh = expected_decision_features(state, "fast", habits=True)
    assert np.array_equal(reused.expected, fresh.expected)
    assert any(a == FeatureQuery() for a in fresh.actions)
    assert not np.array_equal(first.expected[-1], reused.expected[-1])  # the clock moved: not a stale table


def _taught_state(rng):
    state = LearningState(CONCEPTS, [f"f{i}" for i in range(5)], budget=20, turns=20)
    scene, labels = _rows(rng, 12)
    state.observe_scene(0, scene)
    state.apply(LabelQuery(0), labels[0])
    state.apply(LabelQuery(1), labels[1])
    return state, scene, labels


def test_a_quiet_decision_takes_its_learning_columns_from_the_cache_with_the_same_bits(rng):
    state, _, _ = _taught_state(rng)
    expected_decision_features(state, "fast")
    state.apply(NoQuery())
    kept = state.cache["candidates.learned"]
    reused = expected_decision_features(state, "fast")
    assert state.cache["candidates.learned"] is kept  # a hit: nothing recomputed
    state.cache.clear()
    fresh = expected_decision_features(state, "fast")
    assert np.array_equal(reused.expected, fresh.expected) and np.array_equal(reused.current, fresh.current)
    assert reused.actions == fresh.actions


def test_a_new_model_version_or_scene_invalidates_the_decision_cache(rng):
    state, scene, labels = _taught_state(rng)
    expected_decision_features(state, "fast")
    state.apply(LabelQuery(2), labels[2])  # a refit: a new version
    after_answer = expected_decision_features(state, "fast")
    state.observe_scene(1, scene[::-1].copy())  # a new scene (and scaler)
    after_scene = expected_decision_features(state, "fast")
    state.cache.clear()
    assert np.array_equal(after_scene.expected, expected_decision_features(state, "fast").expected)
    assert not np.array_equal(after_answer.expected[:, :4], after_scene.expected[:, :4])


def test_the_candidates_are_kept_while_their_inputs_stay_and_built_anew_when_they_change(rng):
    from learning.decision.candidates import candidate_actions

    state, _, labels = _taught_state(rng)
    first = candidate_actions(state)
    assert candidate_actions(state) is first  # the same objects: the decision cache recognises them
    state.apply(LabelQuery(3), labels[3])
    again = candidate_actions(state)
    assert LabelQuery(3) in first and LabelQuery(3) not in again
    state.cache.clear()
    assert candidate_actions(state) == again
    state.place_progress(spent=18.5)  # only the label query is still affordable
    cheap = candidate_actions(state)
    assert cheap == tuple(a for a in again if a.kind in ("label", "none")) and len(cheap) < len(again)


def test_computed_feature_subsets_are_kept_per_training_set_and_recomputed_when_it_changes(rng):
    from learning.features.selection import computational_subsets

    state = LearningState(CONCEPTS, [f"f{i}" for i in range(5)], budget=40, turns=40, feature_selection="ES")
    scene, labels = _rows(rng, 20)
    state.observe_scene(0, scene)
    for i in range(8):
        state.apply(LabelQuery(i), labels[i])
    kept = state._selected
    state.observe_scene(1, rng.normal(size=(20, 5)))  # a scene change refits with the same training set
    assert state._selected is kept
    X, taught = state.training_matrix()
    fresh = computational_subsets(X, taught, CONCEPTS, method="ES")
    for c in CONCEPTS:
        assert np.array_equal(state.fitted_feature_subsets[c], fresh[c])
    state.apply(LabelQuery(8), labels[8])  # a new training set: selected anew
    assert state._selected is not kept
    X, taught = state.training_matrix()
    assert all(np.array_equal(state._selected[1][c], s)
               for c, s in computational_subsets(X, taught, CONCEPTS, method="ES").items())


def test_the_counts_are_kept_per_training_set_and_handed_out_as_a_new_dict(rng):
    state, _, labels = _taught_state(rng)
    counts = state.counts_per_concept()
    counts["a"] += 100  # the caller's copy
    assert state.counts_per_concept() == {c: int(sum(labels[:2] == c)) for c in CONCEPTS}
    state.apply(LabelQuery(2), labels[2])
    assert state.counts_per_concept() == {c: int(sum(labels[:3] == c)) for c in CONCEPTS}


@pytest.mark.parametrize("indices", [np.array([3, 1, 3]), np.array([0], dtype=np.uint8), [2, 0], 4])
def test_integer_subsets_take_the_short_check_with_the_same_result(indices):
    from learning.concepts import checked_subset

    assert np.array_equal(checked_subset(indices, 5), np.unique(np.asarray(indices).reshape(-1)))
    with pytest.raises(ValueError, match="within 0..1"):
        checked_subset(np.array([0, 2]), 2)


def test_batched_newton_steps_give_each_row_the_bits_of_its_own_fit(rng):
    from learning.gp import newton_modes

    X = rng.normal(size=(35, 4))
    K = rbf_kernel(X, X, 2.0, 4.0)
    targets = np.where(rng.random((5, 35)) < [[0.1], [0.5], [0.9], [0.3], [0.0]], 1.0, -1.0)  # rows converge apart
    f, sw = newton_modes(K, targets, 30, 1e-6)
    for row, t in enumerate(targets):
        alone = BinaryGPClassifier().fit(X, t > 0, kernel=K)
        assert np.array_equal(f[row], alone.f_hat_) and np.array_equal(sw[row], alone.W_sqrt_)


def test_read_only_held_out_rows_are_scaled_once_per_scaler_with_the_same_bits(rng):
    state, _, _ = _taught_state(rng)
    held_out = rng.normal(size=(50, 5))
    held_out.setflags(write=False)
    first = state.probabilities(held_out)
    kept = state._rows_kept
    assert np.array_equal(state.probabilities(held_out), first) and state._rows_kept is kept  # a hit
    state.observe_scene(1, rng.normal(size=(12, 5)) * 3.0)  # a wider scaler pool: scaled anew
    moved = state.probabilities(held_out)
    assert state._rows_kept is not kept
    assert np.array_equal(moved, state.probabilities(held_out.copy()))  # a writable copy: scaled, never kept
    writable = held_out.copy()
    state.probabilities(writable)
    assert state._rows_kept[0] is held_out
