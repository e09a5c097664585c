"""One binary GP classifier per concept, each on its own feature subset (thesis §6.3).

A labelled instance joins every concept's training set: positive for its own
concept, negative for the others.
"""

from __future__ import annotations

from numbers import Real

import numpy as np

from learning.gp import BinaryGPClassifier, rbf_kernel

# A feature whose observed spread is below this fraction of its magnitude (or of 1) has shown no
# variation yet; it keeps unit scale instead of blowing small test differences up to huge z-scores.
RELATIVE_STD_FLOOR = 1e-3


def _real_array(values, refusal: str) -> np.ndarray:
    """``values`` as a float array when they are real numbers (ints or floats), else ValueError(``refusal``)."""
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raise ValueError(refusal) from None
    kind = raw.dtype.kind
    if kind == "O":
        wrong = [v for v in raw.reshape(-1) if isinstance(v, (bool, np.bool_)) or not isinstance(v, (Real, np.number))
                 or isinstance(v, (complex, np.complexfloating))]
        if wrong:
            raise ValueError(f"{refusal}, got {wrong[0]!r} ({type(wrong[0]).__name__})")
    elif kind not in "iuf":
        shown = {"c": "complex numbers", "b": "booleans", "U": "text", "S": "bytes"}.get(kind, f"dtype {raw.dtype}")
        raise ValueError(f"{refusal}, got {shown}")
    try:
        return np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(refusal) from None


def checked_rows(X, n_features: int, what: str = "rows") -> np.ndarray:
    """``X`` as a finite float (n, n_features) matrix; a ValueError naming the problem otherwise. Only real
    numbers are taken: complex values (which numpy would cast to their real part), booleans and text are refused."""
    X = _real_array(X, f"{what} must be real numbers in an (n, {n_features}) matrix")
    if X.ndim != 2 or X.shape[1] != n_features:
        raise ValueError(f"{what} must be an (n, {n_features}) matrix, got shape {X.shape}")
    bad = ~np.isfinite(X)
    if bad.any():
        row, column = (int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{what} must be finite numbers: {int(bad.sum())} value(s) are NaN or infinite, the first "
                         f"at row {row}, column {column}")
    return X


def checked_row(x, n_features: int, what: str = "row") -> np.ndarray:
    """``x`` as a finite float vector of ``n_features`` values; a ValueError naming the problem otherwise."""
    x = _real_array(x, f"{what} must be {n_features} real numbers")
    if x.shape != (n_features,):
        raise ValueError(f"{what} must hold {n_features} feature values, got shape {x.shape}")
    return checked_rows(x[None, :], n_features, what)[0]


class FeatureScaler:
    """Standardise features with the mean and spread of every instance observed so far."""

    def __init__(self, n_features: int):
        self.n_features = int(n_features)
        self._sum = np.zeros(n_features)
        self._sq = np.zeros(n_features)
        self._count = 0

    def update(self, X: np.ndarray) -> None:
        """Widen the pool with rows ``X`` (checked first: a bad matrix leaves the scaler unchanged)."""
        X = checked_rows(X, self.n_features, "scaler rows")
        self._sum += X.sum(axis=0)
        self._sq += (X * X).sum(axis=0)
        self._count += len(X)

    def copy(self) -> FeatureScaler:
        twin = FeatureScaler(self.n_features)
        twin._sum, twin._sq, twin._count = self._sum.copy(), self._sq.copy(), self._count
        return twin

    @property
    def mean(self) -> np.ndarray:
        return self._sum / max(self._count, 1)

    @property
    def std(self) -> np.ndarray:
        if self._count == 0:
            return np.ones_like(self._sum)
        mean = self.mean
        spread = np.sqrt(np.maximum(self._sq / self._count - mean**2, 0.0))
        floor = RELATIVE_STD_FLOOR * np.maximum(np.abs(mean), 1.0)
        return np.where(spread > floor, spread, 1.0)

    def transform(self, X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        if X.shape[-1:] != (self.n_features,):
            raise ValueError(f"rows to scale must have {self.n_features} features, got shape {X.shape}")
        return (X - self.mean) / self.std


class ConceptModels:
    """The set of per-concept classifiers; ``predict`` gives p(y|x) for every object and concept."""

    def __init__(self, concepts, variance: float = 4.0, length_scale: float | None = None):
        self.concepts = tuple(concepts)
        self.variance = variance
        self.length_scale = length_scale

    def fit(self, X: np.ndarray, labels, subsets: dict[str, np.ndarray | None]) -> ConceptModels:
        """Fit every concept on standardised rows ``X`` with concept names ``labels``; everything is checked
        before anything is replaced, so a bad call keeps the previous fit."""
        X = np.asarray(X, dtype=float)
        if X.ndim != 2:
            raise ValueError(f"training rows must be a 2-D matrix, got shape {X.shape}")
        X = checked_rows(X, X.shape[1], "training rows")
        labels = np.asarray(labels, dtype=object).reshape(-1)
        if len(labels) != len(X):
            raise ValueError(f"{len(X)} training rows but {len(labels)} labels")
        unknown = sorted({str(label) for label in labels} - set(self.concepts))
        if unknown:
            raise ValueError(f"unknown concept(s) {', '.join(unknown)}; known: {', '.join(self.concepts)}")
        for concept, subset in subsets.items():
            if subset is not None and len(subset):  # None or empty: all features
                checked_subset(subset, X.shape[1], f"feature subset of '{concept}'")
        previous = getattr(self, "subsets_", None)
        fitted = getattr(self, "models_", {})  # an answer that only adds rows updates these (BinaryGPClassifier.fit)
        self.subsets_ = {c: subsets.get(c) for c in self.concepts}
        models = {}
        kernels: dict[tuple, np.ndarray] = {}  # a fresh fit's kernel, shared by the concepts on the same columns
        pending: dict[tuple, list[BinaryGPClassifier]] = {}  # fresh fits on one kernel: one batch of Newton steps
        try:
            for concept in self.concepts:
                columns = self.columns(concept, X.shape[1])
                key = tuple(columns.tolist())
                model = BinaryGPClassifier(self.length_scale, self.variance).fit(
                    X[:, columns], labels == concept, previous=fitted.get(concept), kernel=kernels.get(key),
                    defer_newton=True)
                if len(X) and not model.incremental_:
                    kernels.setdefault(key, model.K_)
                    pending.setdefault(key, []).append(model)
                models[concept] = model
            for group in pending.values():
                BinaryGPClassifier.fit_together(group)
        except Exception:
            if previous is None:
                del self.subsets_
            else:
                self.subsets_ = previous
            raise
        self.models_ = models
        return self

    def columns(self, concept: str, n_features: int) -> np.ndarray:
        """The feature columns the classifier of ``concept`` uses (all when it has no subset)."""
        subset = self.subsets_.get(concept)
        return np.arange(n_features) if subset is None or len(subset) == 0 else np.asarray(subset)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """(n, |Y|) matrix of p(y | x) for standardised rows ``X``.

        The concepts on the same columns share their training rows, so the kernel between those rows and ``X``
        is computed once for all of them (the same bits each would compute)."""
        shared: dict[tuple, tuple[np.ndarray, np.ndarray | None]] = {}
        columns_of_X = []
        for concept in self.concepts:
            model, columns = self.models_[concept], self.columns(concept, X.shape[1])
            key = tuple(columns.tolist())
            if key not in shared:
                rows = X[:, columns]
                fitted = len(model.targets_) > 0
                shared[key] = (rows, rbf_kernel(model.X_train_, rows, model.length_scale_, model.variance)
                               if fitted else None)
            columns_of_X.append(model.predict_proba(*shared[key]))
        return np.column_stack(columns_of_X)


def checked_subset(indices, n_features: int, what: str = "feature indices") -> np.ndarray:
    """Sorted unique whole-number column indices, non-empty and within ``0..n_features - 1``."""
    if isinstance(indices, np.ndarray) and indices.dtype.kind in "iu" and indices.ndim == 1 and len(indices):
        values = np.unique(indices.astype(int))  # whole numbers already: the element checks below would pass
    else:
        values = np.asarray(indices if np.ndim(indices) else [indices], dtype=object).reshape(-1)
        if len(values) == 0:
            raise ValueError(f"{what} must name at least one feature (indices 0..{n_features - 1})")
        wrong = [v for v in values if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer))]
        if wrong:
            raise ValueError(f"{what} must be whole-number feature indices 0..{n_features - 1}, got {wrong[0]!r}")
        values = np.unique(values.astype(int))
    outside = values[(values < 0) | (values >= n_features)]
    if len(outside):
        raise ValueError(f"{what} must be within 0..{n_features - 1}, got {outside[0]}")
    return values


def normalise_rows(P: np.ndarray) -> np.ndarray:
    """Turn per-concept probabilities into a distribution over concepts per object."""
    total = P.sum(axis=1, keepdims=True)
    return np.where(total > 0, P / np.maximum(total, 1e-300), 1.0 / P.shape[1])


def entropy(P: np.ndarray) -> np.ndarray:
    """H(y|x) = -sum_y P(y|x) log P(y|x) per row (thesis eq. 6.1), on normalised rows."""
    Q = normalise_rows(P)
    return -np.sum(np.where(Q > 0, Q * np.log(np.maximum(Q, 1e-300)), 0.0), axis=1)
