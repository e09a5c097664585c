"""Paired comparisons across participants: Wilcoxon signed-rank with the matched-pairs rank-biserial effect size."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import wilcoxon

from learning.significance import rank_biserial


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
