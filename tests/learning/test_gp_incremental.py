"""Incremental Laplace refits (an answer appends a row) equal fresh fits within the Newton tolerance."""

import numpy as np
import pytest

from learning.concepts import ConceptModels
from learning.gp import BinaryGPClassifier
from learning.synthetic import SyntheticTask, random_state

TOLERANCE = 1e-6  # the fit's own Newton tolerance


def task_rows(seed: int, n: int):
    task = SyntheticTask(seed=seed)
    X, labels = task.sample(n, np.random.default_rng(seed))
    return (X - X.mean(axis=0)) / X.std(axis=0), labels


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_each_answer_updates_the_fit_to_what_a_fresh_fit_gives(seed):
    X, labels = task_rows(seed, 180)
    y, held_out = labels[:130] == "fruit", X[130:]
    model = BinaryGPClassifier(incremental_from=1).fit(X[:3], y[:3])
    for n in range(4, 130, 9):  # answers one row at a time from 3 rows, every ninth checked
        for m in range(len(model.targets_) + 1, n + 1):
            model = BinaryGPClassifier(incremental_from=1).fit(X[:m], y[:m], previous=model)
            assert model.incremental_
        fresh = BinaryGPClassifier().fit(X[:n], y[:n])
        assert np.max(np.abs(model.predict_proba(held_out) - fresh.predict_proba(held_out))) < TOLERANCE
        np.testing.assert_allclose(model.f_hat_, fresh.f_hat_, atol=10 * TOLERANCE)


def test_many_rows_at_once_far_from_the_old_mode_still_give_the_fresh_fit():
    X, labels = task_rows(3, 300)
    y = labels == "beverage"
    old = BinaryGPClassifier(incremental_from=1).fit(X[:2], y[:2])
    updated = BinaryGPClassifier(incremental_from=1).fit(X[:250], y[:250], previous=old)
    fresh = BinaryGPClassifier().fit(X[:250], y[:250])
    assert updated.incremental_
    assert np.max(np.abs(updated.predict_proba(X[250:]) - fresh.predict_proba(X[250:]))) < TOLERANCE


def test_anything_but_appended_rows_is_a_fresh_fit():
    X, labels = task_rows(4, 40)
    y = labels == "snack"
    old = BinaryGPClassifier(incremental_from=1).fit(X[:30], y[:30])
    changed = X[:31].copy()
    changed[0, 0] += 1e-9  # a rescaled row (a new scene widens the scaler)
    assert not BinaryGPClassifier(incremental_from=1).fit(changed, y[:31], previous=old).incremental_
    relabelled = y[:31].copy()
    relabelled[3] = not relabelled[3]
    assert not BinaryGPClassifier(incremental_from=1).fit(X[:31], relabelled, previous=old).incremental_
    assert not BinaryGPClassifier(incremental_from=1).fit(X[:30, :5], y[:30], previous=old).incremental_
    assert not BinaryGPClassifier(incremental_from=1, variance=2.0).fit(X[:31], y[:31], previous=old).incremental_
    assert not BinaryGPClassifier().fit(X[:31], y[:31], previous=old).incremental_  # 30 rows: below the default


@pytest.mark.parametrize("seed", [0, 1])
def test_the_learner_updates_its_models_after_answers_and_they_equal_a_fresh_fit(seed):
    task = SyntheticTask(seed=seed)
    rng = np.random.default_rng(seed)
    state = random_state(task, 120, 12, rng, feature_query_answered=seed == 1)
    from learning.actions import LabelQuery

    truth = rng.choice(task.concepts, 12)
    for obj in range(6):  # six label answers in this scene: each appends one row to every concept's set
        state.apply(LabelQuery(obj), str(truth[obj]))
        assert all(state.concept_model(c).incremental_ for c in state.concepts)
    X, labels = state.scaled_training()
    fresh = ConceptModels(state.concepts, variance=state.kernel_variance, length_scale=state.length_scale)
    fresh.fit(X, labels, dict(state.feature_subsets))
    assert np.max(np.abs(state.probabilities() - fresh.predict(state.scaled_scene()))) < TOLERANCE
