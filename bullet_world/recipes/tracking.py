"""Which perceived object after an action is which object before it, from perceived features only.

Perception lists objects in no particular order, so before eq. 4.1 can compare
an object's features before and after an action, the two lists must be
matched. The match is the assignment (Hungarian algorithm) that minimises the
sum over matched pairs of

    cost(i, j) = || ( (a_i - a'_j) / s_a ,  (l_i - l'_j) / s_l ) ||

where a is the appearance (r, g, b, length, width, height), l the location,
and s_a, s_l are scales (appearance noise, and a long distance so that
appearance dominates). The cost is a Euclidean norm, not its square: by the
triangle inequality, swapping a moved object with a look-alike that did not
move can never be cheaper than the true match, so a moved object is matched to
itself even when an identical one stands elsewhere.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from learning.errors import SceneError

APPEARANCE_SCALE = np.array([0.03, 0.03, 0.03, 0.01, 0.01, 0.01])
LOCATION_SCALE_M = 0.5


def match_rows(before_appearance: np.ndarray, before_locations: np.ndarray, after_appearance: np.ndarray,
               after_locations: np.ndarray, appearance_scale: np.ndarray = APPEARANCE_SCALE,
               location_scale: float = LOCATION_SCALE_M) -> np.ndarray:
    """``order`` such that after-row ``order[i]`` is the same object as before-row ``i``.

    Both observations must list the same number of objects; a mismatch raises
    a ValueError naming the counts.
    """
    a0, l0 = np.asarray(before_appearance, float), np.asarray(before_locations, float)
    a1, l1 = np.asarray(after_appearance, float), np.asarray(after_locations, float)
    if a0.shape[0] != a1.shape[0] or l0.shape[0] != a0.shape[0] or l1.shape[0] != a1.shape[0]:
        raise SceneError(f"cannot match {a0.shape[0]} objects before with {a1.shape[0]} after; "
                         "accepted: the same objects seen in both observations")
    scale = np.asarray(appearance_scale, dtype=float)
    appearance = (a0[:, None, :] - a1[None, :, :]) / scale
    location = (l0[:, None, :] - l1[None, :, :]) / float(location_scale)
    cost = np.sqrt(np.sum(appearance**2, axis=2) + np.sum(location**2, axis=2))
    rows, columns = linear_sum_assignment(cost)
    order = np.empty(a0.shape[0], dtype=int)
    order[rows] = columns
    return order
