"""Learning curves and significance tests for comparing questioning strategies (thesis §6.6, §7.4).

The thesis compares strategies with the Mann-Whitney U test on per-data-set
accuracies (eq. 6.4 averages over k training sets); curves are summarised by
their mean and standard error at each point. Where every strategy plays the
same episodes (same pools, seeds and scenes) the comparison is paired: the
Wilcoxon signed-rank test over the shared episodes, its matched-pairs
rank-biserial effect size, a cluster bootstrap interval of the mean
difference (whole clusters resampled: the caller says what the episodes
share; the suites cluster by data seed), and Holm's correction over the
findings of one table.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import mannwhitneyu, rankdata, wilcoxon

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
    p_holm: float | None = None  # Holm-adjusted over the findings of one table (None: not adjusted)

    @property
    def significant(self) -> bool:
        return (self.p if self.p_holm is None else self.p_holm) < 0.05


@dataclass(frozen=True)
class PairedComparison:
    """Wilcoxon signed-rank of ``a`` against ``b`` over ``n`` paired episodes (``greater``: a tends to exceed b),
    the matched-pairs rank-biserial ``effect`` r, the median and mean differences, and a 95 % cluster-bootstrap
    interval ``ci`` of the mean difference a - b over ``clusters`` clusters (None with a single cluster: nothing
    to resample)."""

    a: str
    b: str
    alternative: str
    statistic: float  # W: the signed-rank statistic scipy reports (NaN when the test cannot be run)
    p: float
    mean_a: float
    mean_b: float
    n: int
    median_difference: float
    effect: float
    ci: tuple[float, float] | None
    clusters: int  # the units the interval resampled (the suites': data seeds)
    p_holm: float | None = None

    @property
    def significant(self) -> bool:
        return (self.p if self.p_holm is None else self.p_holm) < 0.05


def rank_biserial(differences) -> float:
    """Matched-pairs rank-biserial r = (R+ - R-) / (R+ + R-) over the ranks of the non-zero |differences|
    (0 when all are zero): +1 when every pair favours a."""
    d = np.asarray(differences, dtype=float)
    d = d[d != 0]
    if len(d) == 0:
        return 0.0
    ranks = rankdata(np.abs(d))
    plus, minus = ranks[d > 0].sum(), ranks[d < 0].sum()
    return float((plus - minus) / (plus + minus))


def cluster_bootstrap_ci(differences, clusters, rng: np.random.Generator, resamples: int = 2000,
                         level: float = 0.95) -> tuple[float, float] | None:
    """Percentile interval of the mean of ``differences`` when whole clusters (e.g. the data seeds, whose
    episodes share a test pool) are resampled with replacement; None for a single cluster (it has no spread
    to resample: no interval rather than a zero-width one). With one difference per cluster it is the plain
    bootstrap."""
    d = np.asarray(differences, dtype=float)
    clusters = list(clusters)
    first_seen = {label: i for i, label in enumerate(dict.fromkeys(clusters))}  # any hashable label, in order
    labels = np.asarray([first_seen[label] for label in clusters], dtype=int)
    if len(d) != len(labels) or len(d) == 0:
        raise ValueError(f"one cluster per difference is needed ({len(d)} differences, {len(labels)} clusters)")
    units = np.unique(labels)
    sums = np.array([d[labels == u].sum() for u in units])
    counts = np.array([np.sum(labels == u) for u in units])
    if len(units) == 1:
        return None
    picks = rng.integers(0, len(units), size=(resamples, len(units)))
    means = sums[picks].sum(axis=1) / counts[picks].sum(axis=1)
    tail = (1.0 - level) / 2.0
    return float(np.quantile(means, tail)), float(np.quantile(means, 1.0 - tail))


def wilcoxon_paired(name_a: str, a, name_b: str, b, alternative: str = "two-sided", clusters=None,
                    rng: np.random.Generator | None = None) -> PairedComparison:
    """Wilcoxon signed-rank test of paired samples ``a`` and ``b`` (one value each per shared episode), zero
    differences dropped as in Wilcoxon's original test; ``clusters`` (one label per pair) for the interval (None:
    every pair its own cluster, the plain bootstrap)."""
    if alternative not in ALTERNATIVES:
        raise ValueError(f"alternative must be one of {', '.join(ALTERNATIVES)}, got '{alternative}'")
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(a) != len(b) or len(a) < 1:
        raise ValueError(f"paired samples need the same number of values, at least one ({name_a}: {len(a)}, "
                         f"{name_b}: {len(b)})")
    d = a - b
    if np.all(d == 0) or len(d) < 2:
        statistic, p = float("nan"), 1.0  # no pair differs: no evidence either way
    else:
        result = wilcoxon(a, b, zero_method="wilcox", alternative=alternative)
        statistic, p = float(result.statistic), float(result.pvalue)
    rng = rng if rng is not None else np.random.default_rng(0)
    labels = list(range(len(d))) if clusters is None else list(clusters)
    ci = cluster_bootstrap_ci(d, labels, rng)
    return PairedComparison(name_a, name_b, alternative, statistic, p, float(a.mean()), float(b.mean()), len(d),
                            float(np.median(d)), rank_biserial(d), ci, len(set(labels)))


def holm(comparisons: list) -> list:
    """The comparisons with ``p_holm`` set: Holm's step-down adjustment over all of them (family-wise 5 %)."""
    m = len(comparisons)
    order = sorted(range(m), key=lambda i: comparisons[i].p)
    adjusted, running = [0.0] * m, 0.0
    for rank, index in enumerate(order):
        running = max(running, min(1.0, (m - rank) * comparisons[index].p))
        adjusted[index] = running
    return [replace(c, p_holm=adjusted[i]) for i, c in enumerate(comparisons)]


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


def ranks_high_first(scores) -> np.ndarray:
    """Rank 1 for the highest score; tied scores share their mean rank."""
    return rankdata(-np.asarray(scores, dtype=float), method="average")


def kendalls_w(ranks, rng: np.random.Generator, resamples: int = 2000) -> dict:
    """Kendall's coefficient of concordance of ``ranks`` (raters x items, ties as mean ranks) with the tie
    correction, W = 12 S / (m^2 (n^3 - n) - m sum T), T = sum (t^3 - t) over a rater's tie groups; Friedman's
    chi-squared m (n - 1) W against n - 1 degrees of freedom; a percentile interval from resampling raters."""
    from scipy.stats import chi2

    ranks = np.asarray(ranks, dtype=float)
    raters, items = ranks.shape
    if raters < 2 or items < 2:
        raise ValueError(f"Kendall's W needs at least 2 raters and 2 items, got {raters} x {items}")

    def w_of(table: np.ndarray) -> float:
        m = len(table)
        totals = table.sum(axis=0)
        spread = float(((totals - totals.mean()) ** 2).sum())
        ties = sum(float((counts ** 3 - counts).sum())
                   for counts in (np.unique(row, return_counts=True)[1] for row in table))
        denominator = m ** 2 * (items ** 3 - items) - m * ties
        return 12.0 * spread / denominator if denominator > 0 else 1.0

    w = w_of(ranks)
    samples = np.array([w_of(ranks[rng.integers(0, raters, raters)]) for _ in range(resamples)])
    statistic = raters * (items - 1) * w
    return {"w": w, "ci": [float(np.quantile(samples, 0.025)), float(np.quantile(samples, 0.975))],
            "chi2": float(statistic), "df": items - 1, "p": float(chi2.sf(statistic, items - 1))}
