"""Paired comparisons across participants: Wilcoxon signed-rank with the matched-pairs rank-biserial effect size."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import rankdata, wilcoxon


@dataclass(frozen=True)
class PairedTest:
    a: str
    b: str
    n: int  # participants with a value under both
    median_difference: float  # median of a - b
    statistic: float  # Wilcoxon W (the smaller rank sum); NaN when the test cannot be run
    p: float
    effect: float  # rank-biserial r in [-1, 1]: +1 when every participant scored higher under a

    @property
    def runnable(self) -> bool:
        return not np.isnan(self.p)


def rank_biserial(differences) -> float:
    """(R+ - R-) / (R+ + R-) over the ranks of the non-zero |differences| (0 when all are zero)."""
    d = np.asarray(differences, dtype=float)
    d = d[d != 0]
    if len(d) == 0:
        return 0.0
    ranks = rankdata(np.abs(d))
    plus, minus = ranks[d > 0].sum(), ranks[d < 0].sum()
    return float((plus - minus) / (plus + minus))


def paired_test(name_a: str, a: dict, name_b: str, b: dict) -> PairedTest:
    """Wilcoxon signed-rank of a against b over the participants (keys) present in both."""
    shared = sorted(set(a) & set(b))
    x = np.array([a[key] for key in shared], dtype=float)
    y = np.array([b[key] for key in shared], dtype=float)
    d = x - y
    median = float(np.median(d)) if len(d) else float("nan")
    if len(d) < 2 or np.all(d == 0):
        return PairedTest(name_a, name_b, len(d), median, float("nan"), float("nan"), rank_biserial(d))
    result = wilcoxon(x, y, zero_method="wilcox", alternative="two-sided")
    return PairedTest(name_a, name_b, len(d), median, float(result.statistic), float(result.pvalue), rank_biserial(d))
