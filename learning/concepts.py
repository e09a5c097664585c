"""One binary GP classifier per concept, each on its own feature subset (thesis §6.3).

A labelled instance joins every concept's training set: positive for its own
concept, negative for the others.
"""

from __future__ import annotations

import numpy as np

from learning.gp import BinaryGPClassifier

# A feature whose observed spread is below this fraction of its magnitude (or of 1) has shown no
# variation yet; it keeps unit scale instead of blowing small test differences up to huge z-scores.
RELATIVE_STD_FLOOR = 1e-3


class FeatureScaler:
    """Standardise features with the mean and spread of every instance observed so far."""

    def __init__(self, n_features: int):
        self._sum = np.zeros(n_features)
        self._sq = np.zeros(n_features)
        self._count = 0

    def update(self, X: np.ndarray) -> None:
        self._sum += X.sum(axis=0)
        self._sq += (X * X).sum(axis=0)
        self._count += len(X)

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
        return (X - self.mean) / self.std


class ConceptModels:
    """The set of per-concept classifiers; ``predict`` gives p(y|x) for every object and concept."""

    def __init__(self, concepts, variance: float = 4.0, length_scale: float | None = None):
        self.concepts = tuple(concepts)
        self.variance = variance
        self.length_scale = length_scale

    def fit(self, X: np.ndarray, labels, subsets: dict[str, np.ndarray | None]) -> ConceptModels:
        """Fit every concept on standardised rows ``X`` with concept names ``labels``."""
        labels = np.asarray(labels, dtype=object)
        self.subsets_ = {c: subsets.get(c) for c in self.concepts}
        self.models_ = {}
        for concept in self.concepts:
            columns = self.columns(concept, X.shape[1])
            model = BinaryGPClassifier(self.length_scale, self.variance)
            self.models_[concept] = model.fit(X[:, columns], labels == concept)
        return self

    def columns(self, concept: str, n_features: int) -> np.ndarray:
        """The feature columns the classifier of ``concept`` uses (all when it has no subset)."""
        subset = self.subsets_.get(concept)
        return np.arange(n_features) if subset is None or len(subset) == 0 else np.asarray(subset)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """(n, |Y|) matrix of p(y | x) for standardised rows ``X``."""
        return np.column_stack([
            self.models_[c].predict_proba(X[:, self.columns(c, X.shape[1])]) for c in self.concepts
        ])


def normalise_rows(P: np.ndarray) -> np.ndarray:
    """Turn per-concept probabilities into a distribution over concepts per object."""
    total = P.sum(axis=1, keepdims=True)
    return np.where(total > 0, P / np.maximum(total, 1e-300), 1.0 / P.shape[1])


def entropy(P: np.ndarray) -> np.ndarray:
    """H(y|x) = -sum_y P(y|x) log P(y|x) per row (thesis eq. 6.1), on normalised rows."""
    Q = normalise_rows(P)
    return -np.sum(np.where(Q > 0, Q * np.log(np.maximum(Q, 1e-300)), 0.0), axis=1)
