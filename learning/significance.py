"""Learning curves and significance tests for comparing questioning strategies (thesis §6.6, §7.4).

The thesis compares strategies with the Mann-Whitney U test on per-data-set
accuracies (eq. 6.4 averages over k training sets); curves are summarised by
their mean and standard error at each point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import mannwhitneyu

ALTERNATIVES = ("two-sided", "greater", "less")


@dataclass(frozen=True)
class Comparison:
    """Mann-Whitney U of sample ``a`` against ``b``; ``greater`` asks whether a tends to exceed b."""

    a: str
    b: str
    alternative: str
    u: float
    p: float
    mean_a: float
    mean_b: float
    n_a: int
    n_b: int

    @property
    def significant(self) -> bool:
        return self.p < 0.05


def mann_whitney(name_a: str, a, name_b: str, b, alternative: str = "two-sided") -> Comparison:
    """Mann-Whitney U test between two samples of accuracies."""
    if alternative not in ALTERNATIVES:
        raise ValueError(f"alternative must be one of {', '.join(ALTERNATIVES)}, got '{alternative}'")
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(a) < 1 or len(b) < 1:
        raise ValueError(f"both samples need at least one value ({name_a}: {len(a)}, {name_b}: {len(b)})")
    if np.all(a == a[0]) and np.all(b == a[0]):
        u, p = len(a) * len(b) / 2.0, 1.0  # identical constant samples: no evidence either way
    else:
        result = mannwhitneyu(a, b, alternative=alternative, method="auto")
        u, p = float(result.statistic), float(result.pvalue)
    return Comparison(name_a, name_b, alternative, u, p, float(a.mean()), float(b.mean()), len(a), len(b))


def mean_and_standard_error(curves: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Column-wise mean and standard error of a (runs x points) array; NaN entries are ignored.

    A column with no values gives NaN; a column with one value has standard error 0.
    """
    curves = np.asarray(curves, dtype=float)
    if curves.ndim != 2:
        raise ValueError(f"curves must be a (runs x points) array, got shape {curves.shape}")
    counts = np.sum(~np.isnan(curves), axis=0)
    filled = np.where(np.isnan(curves), 0.0, curves)
    mean = np.where(counts > 0, filled.sum(axis=0) / np.maximum(counts, 1), np.nan)
    squares = np.where(np.isnan(curves), 0.0, (curves - mean) ** 2).sum(axis=0)
    std = np.sqrt(squares / np.maximum(counts - 1, 1))
    error = np.where(counts > 1, std / np.sqrt(np.maximum(counts, 1)), np.where(counts == 1, 0.0, np.nan))
    return mean, error


def accuracy_after_questions(questions: np.ndarray, accuracy: np.ndarray, checkpoints) -> np.ndarray:
    """Accuracy once ``q`` questions had been asked, for each checkpoint q (NaN if never reached).

    ``questions`` and ``accuracy`` are per-turn series of one episode; the value
    at q is the accuracy at the end of the first turn in which the q-th
    question was answered, or the final accuracy for q = 0 before any question.
    """
    questions, accuracy = np.asarray(questions), np.asarray(accuracy, dtype=float)
    values = []
    for q in checkpoints:
        reached = np.nonzero(questions >= q)[0]
        values.append(accuracy[reached[0]] if len(reached) else np.nan)
    return np.array(values)
