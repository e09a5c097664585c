"""How finely DT tells expected utilities apart: one resolution for the strategy, its embodied rule and IRL.

Expected utilities closer than ``EU_RESOLUTION`` x max(1, |EU|) are equal. The what-if engine's
single-precision factor holds probabilities to 1e-7 of double precision (tests/learning/test_gp.py), so a
smaller difference is rounding: it must not choose between two equally good questions (an engine change
would flip the choice) nor between a question and staying quiet (eq. 7.1: a query is asked only when its
EU beats EU(no query)).
"""

from __future__ import annotations

import numpy as np

EU_RESOLUTION = 1e-6


def first_of_best(values: np.ndarray, margin: float) -> int:
    """The first index whose value is within ``margin`` of the largest: ties (up to rounding) go to the
    first in candidate order."""
    values = np.asarray(values, dtype=float)
    return int(np.flatnonzero(values >= values.max() - margin)[0])
