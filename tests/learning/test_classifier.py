"""ConceptClassifier: scikit-learn's estimator checks, and what the GP-per-class model must do."""

import numpy as np
import pytest
from sklearn.datasets import load_iris
from sklearn.utils.estimator_checks import parametrize_with_checks

from learning import ConceptClassifier

# Every check of scikit-learn 1.9 passes; a check it could not pass would be listed here with the reason.
EXPECTED_FAILED_CHECKS: dict[str, str] = {}


@parametrize_with_checks([ConceptClassifier()], expected_failed_checks=lambda estimator: EXPECTED_FAILED_CHECKS)
def test_scikit_learn_estimator_checks(estimator, check):
    check(estimator)


@pytest.fixture(scope="module")
def iris():
    X, y = load_iris(return_X_y=True)
    order = np.random.default_rng(0).permutation(len(y))
    return X[order], y[order]


def test_learns_iris_from_raw_unscaled_features(iris):
    X, y = iris
    clf = ConceptClassifier().fit(X[:100], y[:100])
    assert list(clf.classes_) == [0, 1, 2]
    P = clf.predict_proba(X[100:])
    assert P.shape == (50, 3) and np.allclose(P.sum(axis=1), 1.0)
    assert np.mean(clf.predict(X[100:]) == y[100:]) > 0.9


def test_inputs_are_scaled_inside(iris):
    X, y = iris
    stretched = X * np.array([1000.0, 1.0, 0.001, 50.0])
    plain = ConceptClassifier().fit(X[:100], y[:100]).predict_proba(X[100:])
    scaled = ConceptClassifier().fit(stretched[:100], y[:100]).predict_proba(stretched[100:])
    assert np.allclose(plain, scaled, atol=1e-8)


def test_string_labels_come_back_as_given(iris):
    X, y = iris
    names = np.array(["setosa", "versicolor", "virginica"])[y]
    clf = ConceptClassifier().fit(X[:100], names[:100])
    assert list(clf.classes_) == ["setosa", "versicolor", "virginica"]
    assert set(clf.predict(X[100:])) <= set(clf.classes_)


def test_partial_fit_equals_one_fit_on_everything(iris):
    X, y = iris
    whole = ConceptClassifier().fit(X[:90], y[:90])
    parts = ConceptClassifier().partial_fit(X[:40], y[:40]).partial_fit(X[40:90], y[40:90])
    assert np.allclose(whole.predict_proba(X[90:]), parts.predict_proba(X[90:]))
    assert len(parts.X_) == 90


def test_partial_fit_learns_classes_named_up_front_or_seen_later(iris):
    X, y = iris
    clf = ConceptClassifier().partial_fit(X[y == 0][:5], y[y == 0][:5], classes=[0, 1, 2])
    assert list(clf.classes_) == [0, 1, 2]
    assert clf.predict_proba(X[:3]).shape == (3, 3)
    later = ConceptClassifier().partial_fit(X[y < 2][:20], y[y < 2][:20])
    assert list(later.classes_) == [0, 1]
    later.partial_fit(X[y == 2][:10], y[y == 2][:10])
    assert list(later.classes_) == [0, 1, 2] and np.mean(later.predict(X) == y) > 0.8


def test_partial_fit_refuses_a_bad_batch_and_keeps_what_it_learned(iris):
    X, y = iris
    clf = ConceptClassifier().fit(X[:30], y[:30])
    before = clf.predict_proba(X[100:])
    with pytest.raises(ValueError, match="features"):
        clf.partial_fit(X[:5, :3], y[:5])
    with pytest.raises(ValueError, match="all text or all numbers"):
        clf.partial_fit(X[:2], np.array(["a", "b"]))
    assert len(clf.X_) == 30 and np.array_equal(clf.predict_proba(X[100:]), before)


def test_a_feature_subset_makes_the_class_ignore_the_other_features(iris):
    X, y = iris
    clf = ConceptClassifier().fit(X[:100], y[:100])
    for cls in clf.classes_:
        assert clf.set_feature_subset(cls, [2, 3]) is clf
    probe = X[100:].copy()
    probe[:, :2] = np.random.default_rng(1).normal(50.0, 10.0, (len(probe), 2))  # change the ignored columns
    assert np.allclose(clf.predict_proba(X[100:]), clf.predict_proba(probe))
    clf.set_feature_subset(0, None)  # class 0 uses every feature again
    assert 0 not in clf.feature_subsets_
    assert not np.allclose(clf.predict_proba(X[100:]), clf.predict_proba(probe))


def test_a_feature_subset_survives_partial_fit_but_not_fit(iris):
    X, y = iris
    clf = ConceptClassifier().fit(X[:50], y[:50]).set_feature_subset(1, [3])
    clf.partial_fit(X[50:60], y[50:60])
    assert list(clf.feature_subsets_[1]) == [3]
    assert clf.fit(X[:50], y[:50]).feature_subsets_ == {}


def test_bad_subsets_and_parameters_are_clear_errors_that_change_nothing(iris):
    X, y = iris
    clf = ConceptClassifier().fit(X[:50], y[:50]).set_feature_subset(2, [0, 1])
    before = clf.predict_proba(X[100:])
    for cls, features, message in [(7, [0], "unknown class 7"), (0, [4], "within 0..3"), (0, [], "at least one"),
                                   (0, ["petal"], "unknown feature 'petal'"), (0, [1.5], "whole-number")]:
        with pytest.raises(ValueError, match=message):
            clf.set_feature_subset(cls, features)
    assert list(clf.feature_subsets_) == [2] and np.array_equal(clf.predict_proba(X[100:]), before)
    with pytest.raises(ValueError, match="variance must be a positive number"):
        ConceptClassifier(variance=0).fit(X, y)
    with pytest.raises(ValueError, match="length_scale must be None or a positive number"):
        ConceptClassifier(length_scale=-1.0).fit(X, y)
