"""Embodied query costs (thesis §8.2.2): time in seconds instead of turns, and what a query takes to make.

With embodied costs the time allocation T_s is seconds, and every action takes its own expected time:
the arm's motion (a label query points at its object: a far object takes longer), saying the question,
the teacher's answer, and a short quiet turn for no query. The dialog side computes the numbers (from
the motion-time model measured on the real arm, the scene's measured distance and bearing of each
object, and the durations in its data file); here they are plain numbers, so the learning core stays
free of the simulator.

* :class:`SecondsClock` is the time part of a learning state: the allocation, the seconds used, the
  expected seconds of each kind of turn apart from pointing, and each scene object's expected pointing
  seconds. Remaining time reads (T_s - elapsed - E[seconds(a)]) / T_s at an action's own next state
  (eq. 7.1), so a far object's label query leaves less time than a near one's.
* :func:`choose_per_second` is DT's rule with embodied costs: among the queries whose expected utility
  beats staying quiet, the one with the largest expected utility gain per expected second.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from learning.decision.resolution import first_of_best

KINDS = ("label", "demo", "feature", "none")


@dataclass(frozen=True)
class SecondsClock:
    """Seconds allocated and used, and what each action is expected to take (all in seconds).

    turn_seconds: each kind's expected seconds apart from the arm (label, demo, feature: saying the question and
    the teacher's answer; none: a quiet turn). pointing: each current scene object's expected pointing seconds.
    fetch: the expected seconds of fetching an example from the pantry, spent when the teacher has none to show
    (0 where nothing can be fetched); a demonstration's expectation weighs it by the chance that no scene
    object is of the concept.
    """

    allocation: float
    elapsed: float
    turn_seconds: Mapping[str, float]
    pointing: np.ndarray = field(default_factory=lambda: np.zeros(0))
    fetch: float = 0.0

    def __post_init__(self):
        if not (np.isfinite(self.allocation) and self.allocation > 0):
            raise ValueError(f"the seconds allocation must be a positive number, got {self.allocation!r}")
        missing = [kind for kind in KINDS if kind not in self.turn_seconds]
        if missing:
            raise ValueError(f"turn seconds need every kind ({', '.join(KINDS)}); missing {', '.join(missing)}")
        pointing = np.asarray(self.pointing, dtype=float)
        if pointing.ndim != 1 or not np.all(np.isfinite(pointing)) or np.any(pointing < 0):
            raise ValueError("pointing seconds must be one finite number of 0 or more per scene object")
        object.__setattr__(self, "pointing", pointing)

    def expected_seconds(self, action, absent: float = 0.0) -> float:
        """E[seconds(a)]: the kind's seconds, plus pointing for a label query, plus ``absent`` x fetch for a
        demonstration (``absent``: the chance that the teacher has none to show)."""
        seconds = float(self.turn_seconds[action.kind])
        if action.kind == "label":
            seconds += float(self.pointing[action.object_index]) if action.object_index < len(self.pointing) else 0.0
        if action.kind == "demo":
            seconds += absent * self.fetch
        return seconds

    def remaining(self, seconds: float = 0.0) -> float:
        """(T_s - elapsed - seconds) / T_s in [0, 1]."""
        return float(np.clip((self.allocation - self.elapsed - seconds) / self.allocation, 0.0, 1.0))

    def after(self, seconds: float) -> SecondsClock:
        return replace(self, elapsed=self.elapsed + float(seconds))

    @property
    def used_up(self) -> bool:
        return self.elapsed >= self.allocation


def absent_chance(P: np.ndarray) -> np.ndarray:
    """For every concept, the chance that no scene object is of it: prod_x (1 - p(y|x)) over the scene (|Y|,)."""
    P = np.asarray(P, dtype=float)
    if P.shape[0] == 0:
        return np.ones(P.shape[1])
    return np.prod(np.clip(1.0 - P, 0.0, 1.0), axis=0)


def choose_per_second(utilities: np.ndarray, seconds: np.ndarray, tolerance: float) -> int:
    """DT's choice with embodied costs (thesis §8.2.2 on eq. 7.1; the last row is no query).

    Gain(a) = EU(a) - EU(no query), both at their own next states (eq. 7.1). Among the queries with a gain
    above ``tolerance`` x max(1, |EU(no query)|), take the one with the largest gain per expected second,
    Gain(a) / E[seconds(a)]; rates within a relative ``tolerance`` of the largest are a tie, which goes to
    the first in candidate order. No query when none gains. So a query is still asked only when it beats
    staying quiet (as without embodied costs), and of two equally useful questions the quicker one is asked:
    a near object before a far one.
    """
    utilities, seconds = np.asarray(utilities, dtype=float), np.asarray(seconds, dtype=float)
    stay = utilities[-1]
    gains = utilities[:-1] - stay
    worth = gains > tolerance * max(1.0, abs(stay))
    if not worth.any():
        return len(utilities) - 1
    rate = np.where(worth, gains / np.maximum(seconds[:-1], 1e-9), -np.inf)
    return first_of_best(rate, tolerance * float(rate.max()))
