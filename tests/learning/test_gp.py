"""The binary GP classifier on small arrays."""

import numpy as np
import pytest
from sklearn.gaussian_process import GaussianProcessClassifier
from sklearn.gaussian_process.kernels import RBF, ConstantKernel

from learning.gp import BinaryGPClassifier


def separable(rng, n=80, d=3):
    X = rng.normal(size=(n, d))
    return X, (X[:, 0] + 0.5 * X[:, 1] > 0).astype(int)


def test_learns_a_separable_concept(rng):
    X, y = separable(rng)
    X_test, y_test = separable(rng, 200)
    model = BinaryGPClassifier(length_scale=1.5).fit(X, y)
    assert np.mean((model.predict_proba(X_test) > 0.5) == y_test) > 0.85


def test_agrees_with_scikit_learn_laplace_gpc(rng):
    X, y = separable(rng)
    X_test = rng.normal(size=(30, 3))
    ours = BinaryGPClassifier(length_scale=1.5, variance=4.0).fit(X, y).predict_proba(X_test)
    kernel = ConstantKernel(4.0, "fixed") * RBF(1.5, "fixed")
    theirs = GaussianProcessClassifier(kernel=kernel, optimizer=None).fit(X, y).predict_proba(X_test)[:, 1]
    assert np.max(np.abs(ours - theirs)) < 0.03


def test_no_data_gives_the_prior(rng):
    model = BinaryGPClassifier().fit(np.zeros((0, 4)), np.zeros(0))
    assert np.allclose(model.predict_proba(rng.normal(size=(5, 4))), 0.5)


def test_one_example_leans_positive_near_it_and_prior_far_away():
    model = BinaryGPClassifier(length_scale=1.0).fit(np.zeros((1, 2)), [1])
    near, far = model.predict_proba(np.array([[0.0, 0.0], [10.0, 10.0]]))
    assert near > 0.6
    assert far == pytest.approx(0.5, abs=1e-6)


def test_shape_mismatch_is_a_clear_error():
    with pytest.raises(ValueError, match="one row per label"):
        BinaryGPClassifier().fit(np.zeros((3, 2)), [1, 0])


def test_concept_models_start_from_the_prior_and_learn_from_one_example(rng):
    from learning.concepts import ConceptModels

    models = ConceptModels(("a", "b", "c"), length_scale=1.0)
    assert models.variance == 4.0 and not hasattr(models, "models_")  # the constructor only stores parameters
    X = rng.normal(size=(4, 2))
    assert models.fit(np.zeros((0, 2)), [], {}) is models
    assert np.allclose(models.predict(X), 0.5)
    models.fit(np.zeros((1, 2)), ["b"], {"a": np.array([1])})
    near = models.predict(np.zeros((1, 2)))[0]
    assert near[1] > 0.6 and near[0] == pytest.approx(0.5, abs=0.2) and near[2] < 0.4
    assert models.columns("a", 2).tolist() == [1] and models.columns("b", 2).tolist() == [0, 1]


def test_a_feature_constant_so_far_does_not_swamp_the_others():
    """A feature with no spread in what was observed keeps unit scale: a tiny test difference stays tiny."""
    from learning.concepts import FeatureScaler

    scaler = FeatureScaler(2)
    scaler.update(np.array([[0.0, 0.02], [1.0, 0.02], [2.0, 0.02]]))
    z = scaler.transform(np.array([[1.0, 0.03]]))
    assert abs(z[0, 0]) < 1e-9
    assert abs(z[0, 1]) < 0.1  # was 1e4 with an absolute 1e-6 floor
    assert np.allclose(scaler.std[0], np.sqrt(2 / 3))


@pytest.mark.parametrize("columns", [slice(None), [0, 1], [0]])
def test_the_float32_factor_at_the_mode_predicts_what_double_precision_does(columns):
    """``mode_factor`` is single precision: the predictive probabilities of R&W algorithm 3.2 with a float64
    factor of the same B may differ by far less than the Newton tolerance (1e-6); measured ~1e-8."""
    from learning.gp import rbf_kernel, sigmoid
    from learning.synthetic import SyntheticTask

    task = SyntheticTask(seed=5)
    X, labels = task.sample(400, np.random.default_rng(5))
    X = ((X - X.mean(axis=0)) / X.std(axis=0))[:, columns]
    train, held_out, y = X[:300], X[300:], labels[:300] == "fruit"
    model = BinaryGPClassifier().fit(train, y)
    assert model.L_[0].dtype == np.float32
    sw = model.W_sqrt_
    L64 = np.linalg.cholesky(np.eye(len(sw)) + sw[:, None] * model.K_ * sw[None, :])
    Ks = rbf_kernel(train, held_out, model.length_scale_, model.variance)
    v = np.linalg.solve(L64, sw[:, None] * Ks)
    var = model.variance - np.sum(v * v, axis=0)
    double = sigmoid((Ks.T @ model.grad_) / np.sqrt(1.0 + np.pi * var / 8.0))
    assert np.max(np.abs(model.predict_proba(held_out) - double)) < 1e-7
