"""A scikit-learn classifier of one binary GP per class, built on the learner's own concept models.

``ConceptClassifier`` wraps :class:`learning.concepts.ConceptModels` (one RBF
Gaussian-process classifier per class, each on its own feature subset) and
:class:`learning.concepts.FeatureScaler`, so it takes raw feature matrices and
any class labels. It follows scikit-learn's estimator contract: parameters are
stored in ``__init__``, ``fit`` returns self and learned state ends in ``_``.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted

from learning.concepts import ConceptModels, FeatureScaler, checked_subset, normalise_rows

try:  # scikit-learn >= 1.6
    from sklearn.utils.validation import validate_data
except ImportError:  # older scikit-learn: the same checks as an estimator method
    def validate_data(estimator, *args, **options):
        return estimator._validate_data(*args, **options)


class ConceptClassifier(ClassifierMixin, BaseEstimator):
    """One binary GP classifier (RBF kernel, Laplace approximation) per class; inputs are standardised inside.

    ``length_scale`` None scales with the number of features used (sqrt |F|); ``variance`` is the kernel's
    signal variance. ``predict_proba`` normalises the per-class probabilities over the classes.
    """

    def __init__(self, length_scale: float | None = None, variance: float = 4.0):
        self.length_scale = length_scale
        self.variance = variance

    # -- fitting ----------------------------------------------------------------------
    def fit(self, X, y):
        """Fit on rows ``X`` (n, F) and class labels ``y`` (n,); earlier examples and subsets are forgotten."""
        self._check_parameters()
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        classes, codes = np.unique(y, return_inverse=True)
        scaler = FeatureScaler(X.shape[1])
        scaler.update(X)
        self._install(classes, scaler, X.copy(), codes.reshape(-1), {})
        return self

    def partial_fit(self, X, y, classes=None):
        """Add the examples ``X``, ``y`` to what was learned, with one refit.

        ``classes`` (optional) names every class up front, also those without examples yet; a class first
        seen later simply gets its own GP. The first call on an unfitted classifier starts from nothing.
        """
        first = not hasattr(self, "classes_")
        if first:
            self._check_parameters()
        X, y = validate_data(self, X, y, dtype=np.float64, reset=first)
        check_classification_targets(y)
        old_classes = np.zeros(0, dtype=np.asarray(y).dtype) if first else self.classes_
        known = [old_classes, np.unique(y)] + ([] if classes is None else [np.asarray(classes).reshape(-1)])
        if len({_is_text(part) for part in known if len(part)}) > 1:
            raise ValueError(f"class labels must be all text or all numbers; the known classes are "
                             f"{[_plain(c) for c in old_classes]}, y holds {[_plain(c) for c in np.unique(y)]}")
        try:
            merged = np.unique(np.concatenate(known))
        except (TypeError, ValueError) as error:
            raise ValueError(f"the class labels of y cannot be ordered with the known classes "
                             f"{list(old_classes)} ({error})") from None
        scaler = FeatureScaler(X.shape[1]) if first else self.scaler_.copy()
        scaler.update(X)
        old_labels = old_classes[self.codes_] if not first else np.zeros(0, dtype=merged.dtype)
        labels = np.concatenate([old_labels, y])
        codes = np.searchsorted(merged, labels)
        rows = X.copy() if first else np.vstack([self.X_, X])
        self._install(merged, scaler, rows, codes, {} if first else dict(self.feature_subsets_))
        return self

    def set_feature_subset(self, cls, features):
        """From now on the GP of class ``cls`` uses only ``features`` (column indices, or names when fitted on a
        frame with column names); None gives it every feature again. Refits once; returns self."""
        check_is_fitted(self)
        known = [_plain(c) for c in self.classes_]
        if _plain(cls) not in known:
            raise ValueError(f"unknown class {cls!r}; the classes are {known}")
        subsets = dict(self.feature_subsets_)
        if features is None:
            subsets.pop(_plain(cls), None)
        else:
            subsets[_plain(cls)] = self._feature_indices(features)
        self._install(self.classes_, self.scaler_, self.X_, self.codes_, subsets)
        return self

    def _feature_indices(self, features) -> np.ndarray:
        values = list(features) if np.ndim(features) else [features]
        names = list(getattr(self, "feature_names_in_", []))
        indices = []
        for value in values:
            if isinstance(value, str):
                if value not in names:
                    accepted = f"names {names}" if names else "no names (fitted without column names)"
                    raise ValueError(f"unknown feature {value!r}; accepted: indices 0..{self.n_features_in_ - 1} "
                                     f"or {accepted}")
                indices.append(names.index(value))
            else:
                indices.append(value)
        return checked_subset(indices, self.n_features_in_, "feature subset")

    def _install(self, classes, scaler: FeatureScaler, X: np.ndarray, codes: np.ndarray, subsets: dict) -> None:
        """Fit the per-class models on everything given, then replace the learned state (a failure keeps it)."""
        names = tuple(str(i) for i in range(len(classes)))
        plain = [_plain(c) for c in classes]
        models = ConceptModels(names, variance=self.variance, length_scale=self.length_scale)
        labels = np.array(names, dtype=object)[codes] if len(codes) else np.zeros(0, dtype=object)
        models.fit(scaler.transform(X), labels, {names[plain.index(c)]: s for c, s in subsets.items()})
        self.classes_, self.scaler_, self.X_, self.codes_ = classes, scaler, X, codes
        self.feature_subsets_, self.models_ = subsets, models

    def _check_parameters(self) -> None:
        if not _positive(self.variance):
            raise ValueError(f"variance must be a positive number, got {self.variance!r}")
        if self.length_scale is not None and not _positive(self.length_scale):
            raise ValueError(f"length_scale must be None or a positive number, got {self.length_scale!r}")

    # -- predicting --------------------------------------------------------------------
    def predict_proba(self, X) -> np.ndarray:
        """(n, n_classes) probabilities in the order of ``classes_``; every row sums to 1."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return normalise_rows(self.models_.predict(self.scaler_.transform(X)))

    def predict(self, X) -> np.ndarray:
        """The most probable class of each row."""
        P = self.predict_proba(X)
        return self.classes_[np.argmax(P, axis=1)]


def _positive(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
        and bool(np.isfinite(value)) and bool(value > 0)


def _is_text(labels: np.ndarray) -> bool:
    return labels.dtype.kind in "US" or (labels.dtype.kind == "O" and isinstance(labels.flat[0], str))


def _plain(value):
    """A numpy scalar as the Python value it holds (np.str_('a') -> 'a'); anything else unchanged."""
    return value.item() if isinstance(value, np.generic) else value
