"""Decision features phi(s) in [0, 1] for the decision-theoretic learner (thesis §6.4.2, §7.3.1, eq. 7.2).

U(s) = w . phi(s). The learning features read the scene probabilities
p(y|x) (rows: scene objects, columns: concepts, each column one binary
classifier) and the class counts of the training set; the environment
features read the budget and the clock. Every function accepts a batch: any
leading axes of ``P`` (..., |X|, |Y|) or ``counts`` (..., |Y|) are kept, so one
call scores every simulated next state at once.

Choices the thesis leaves open, made here:

* CDU with no training example at all is 0 (there is no class distribution yet).
* IV divides each concept's coefficient of variation by its largest possible
  value sqrt(|X| - 1) (all mass on one object), so that it lies in [0, 1];
  with one object it is 0.
* PM uses p(y|x) normalised over the concepts (a distribution over labels).
* Non-query time counts the no-query turns in a row that end now, capped by
  the window |T_w| = max(1, round(window_factor * change_every)); it is 0 right
  after a query and 1 after a whole window of silence.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from learning.decision.embodied import SecondsClock

FEATURE_NAMES: tuple[str, ...] = (
    "classifier_discriminability",  # ACD, thesis §6.4.2
    "class_distribution_uniformity",  # CDU, thesis §6.4.2
    "instance_variation",  # IV, eq. 7.3
    "prediction_margin",  # PM, eq. 7.4
    "budget_consumption",  # thesis §7.3.1
    "remaining_time",
    "non_query_time",
)
LEARNING_FEATURES = FEATURE_NAMES[:4]
ENVIRONMENT_FEATURES = FEATURE_NAMES[4:]


def _by_concept(P: np.ndarray) -> np.ndarray:
    """(..., |Y|, |X|) contiguous copy: the reductions over the scene then run along the last axis."""
    return np.ascontiguousarray(np.swapaxes(np.asarray(P, dtype=float), -1, -2))


def discriminability(P: np.ndarray) -> np.ndarray:
    """ACD(s) = mean_y [p(y|x_max) - p(y|x_min)] over the scene (thesis §6.4.2)."""
    return _discriminability(_by_concept(P))


def _discriminability(columns: np.ndarray) -> np.ndarray:
    if columns.shape[-1] == 0:
        return np.zeros(columns.shape[:-2])
    return np.clip((columns.max(axis=-1) - columns.min(axis=-1)).mean(axis=-1), 0.0, 1.0)


def class_uniformity(counts: np.ndarray) -> np.ndarray:
    """CDU(s) = |D_ymin| / |D_ymax| over the positive examples per concept (thesis §6.4.2); 0 with no examples."""
    counts = np.asarray(counts, dtype=float)
    largest = counts.max(axis=-1)
    return np.where(largest > 0, counts.min(axis=-1) / np.maximum(largest, 1.0), 0.0)


def instance_variation(P: np.ndarray) -> np.ndarray:
    """IV(s) = mean_y sigma(p(X|y)) / E[p(X|y)] (eq. 7.3), divided by its maximum sqrt(|X| - 1)."""
    return _instance_variation(_by_concept(P))


def _instance_variation(columns: np.ndarray) -> np.ndarray:
    n_objects = columns.shape[-1]
    if n_objects < 2:
        return np.zeros(columns.shape[:-2])
    mean = columns.mean(axis=-1)
    spread = np.sqrt(np.maximum(np.einsum("...i,...i->...", columns, columns) / n_objects - mean * mean, 0.0))
    variation = np.where(mean > 0, spread / np.maximum(mean, 1e-300), 0.0)
    return np.clip(variation.mean(axis=-1) / np.sqrt(n_objects - 1), 0.0, 1.0)


def label_distribution(P: np.ndarray) -> np.ndarray:
    """p(y|x) normalised over the concepts for every object (uniform where all are 0)."""
    P = np.asarray(P, dtype=float)
    total = P.sum(axis=-1, keepdims=True)
    if np.all(total > 0):
        return P / total
    return np.where(total > 0, P / np.where(total > 0, total, 1.0), 1.0 / P.shape[-1])


def prediction_margin(P: np.ndarray) -> np.ndarray:
    """PM(s) = mean_x [p(y_1|x) - p(y_2|x)], the top two labels of each scene object (eq. 7.4)."""
    return _prediction_margin(_by_concept(P))


def _prediction_margin(columns: np.ndarray) -> np.ndarray:
    """PM from the (..., |Y|, |X|) layout: the sums and top two over the few concepts run on whole rows
    (contiguous), the same additions in the same order as ``label_distribution`` over the last axis."""
    n_concepts, n_objects = columns.shape[-2:]
    if n_objects == 0:
        return np.zeros(columns.shape[:-2])
    total = columns.sum(axis=-2, keepdims=True)
    if np.all(total > 0):
        Q = columns / total
    else:
        Q = np.where(total > 0, columns / np.where(total > 0, total, 1.0), 1.0 / n_concepts)
    if n_concepts == 1:
        return Q[..., 0, :].mean(axis=-1)
    first, second = _top_two(Q, axis=-2)
    return np.clip((first - second).mean(axis=-1), 0.0, 1.0)


def _top_two(Q: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """The largest and second-largest value along ``axis`` (the same numbers np.partition picks).

    One pass over the few concepts with elementwise max/min: a partition of length-|Y| rows costs more
    than the rest of the decision features together.
    """
    Q = np.moveaxis(Q, axis, 0)  # a view: Q[k] is every value of concept k
    first = np.maximum(Q[0], Q[1])
    second = np.minimum(Q[0], Q[1])
    for k in range(2, Q.shape[0]):
        column = Q[k]
        second = np.maximum(second, np.minimum(first, column))
        first = np.maximum(first, column)
    return first, second


@dataclass(frozen=True)
class Clock:
    """The environment part of a learning state: budget, time allocation and recent silence (thesis §7.3.1)."""

    spent: float
    budget: float
    turn: int  # turns finished so far
    turns: int  # the time allocation T
    quiet_run: int  # no-query turns in a row that end now
    window: int  # |T_w|, in turns
    seconds: SecondsClock | None = None  # embodied costs (thesis §8.2.2): the allocation in seconds, else turns

    def budget_consumption(self) -> float:
        """Fraction of the query budget spent; a zero budget counts as spent."""
        return 1.0 if self.budget <= 0 else float(np.clip(self.spent / self.budget, 0.0, 1.0))

    def remaining_time(self) -> float:
        """Fraction of the allocated turns still to come; with embodied costs, of the allocated seconds."""
        if self.seconds is not None:
            return self.seconds.remaining()
        return float(np.clip((self.turns - self.turn) / self.turns, 0.0, 1.0))

    def non_query_time(self) -> float:
        """t_NQ = n_NQ / |T_w| (thesis §7.3.1): 0 right after a query, 1 after a window of silence."""
        return min(self.quiet_run, self.window) / self.window

    def after(self, cost: float, asked: bool, seconds: float = 0.0) -> Clock:
        """The clock one turn later, having spent ``cost`` on a query (``asked``) or stayed quiet; with embodied
        costs the turn took ``seconds``."""
        return Clock(self.spent + cost, self.budget, self.turn + 1, self.turns,
                     0 if asked else self.quiet_run + 1, self.window,
                     None if self.seconds is None else self.seconds.after(seconds))

    def features(self) -> np.ndarray:
        return np.array([self.budget_consumption(), self.remaining_time(), self.non_query_time()])


def window_turns(change_every: int, window_factor: float = 1.0) -> int:
    """|T_w|, proportional to the rate of environmental change (thesis §7.3.1)."""
    if not np.isfinite(window_factor) or window_factor <= 0:
        raise ValueError(f"window_factor must be a positive number, got {window_factor!r}")
    return max(1, int(round(window_factor * change_every)))


def state_clock(state, window_factor: float = 1.0, seconds: bool = True) -> Clock:
    """The clock of a LearningState now; ``seconds`` False ignores embodied costs (time in turns)."""
    return Clock(state.spent, state.budget, state.turn, state.turns, state.quiet_run(),
                 window_turns(state.change_every, window_factor),
                 getattr(state, "seconds_clock", None) if seconds else None)


def learning_features(P: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(..., 4) ACD, CDU, IV, PM for scene probabilities ``P`` (..., |X|, |Y|) and class counts (..., |Y|)."""
    P = np.asarray(P, dtype=float)
    counts = np.broadcast_to(np.asarray(counts, dtype=float), P.shape[:-2] + (P.shape[-1],))
    columns = _by_concept(P)
    return np.stack([_discriminability(columns), class_uniformity(counts), _instance_variation(columns),
                     _prediction_margin(columns)], axis=-1)


def features(P: np.ndarray, counts: np.ndarray, clock: Clock) -> np.ndarray:
    """phi(s) (..., 7) in FEATURE_NAMES order."""
    learned = learning_features(P, counts)
    environment = np.broadcast_to(clock.features(), learned.shape[:-1] + (3,))
    return np.concatenate([learned, environment], axis=-1)


def concept_counts(state) -> np.ndarray:
    """Positive examples per concept of a LearningState, in its concept order."""
    counts = state.counts_per_concept()
    return np.array([counts[c] for c in state.concepts], dtype=float)


def state_features(state, window_factor: float = 1.0) -> np.ndarray:
    """phi(s) of a LearningState as it is now (7,), in FEATURE_NAMES order."""
    return features(state.probabilities(), concept_counts(state), state_clock(state, window_factor))


# a decision feature's name: a TOML bare key (weights files, demonstrations)
FEATURE_NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")


def check_feature_names(names: Sequence[str], source: str = "feature names") -> tuple[str, ...]:
    """Decision-feature names: non-empty, distinct, letters/digits/_/- starting with a letter (TOML bare keys)."""
    if isinstance(names, str) or not isinstance(names, Sequence) or len(names) == 0:
        raise ValueError(f"{source}: expected a non-empty list of decision-feature names, got {names!r}")
    names = tuple(names)
    for name in names:
        if not isinstance(name, str) or not FEATURE_NAME_PATTERN.match(name):
            raise ValueError(f"{source}: feature name {name!r} is not accepted; use letters, digits, '_' or '-', "
                             "starting with a letter")
    if len(set(names)) != len(names):
        duplicates = sorted({n for n in names if names.count(n) > 1})
        raise ValueError(f"{source}: feature names must be distinct; repeated: {', '.join(duplicates)}")
    return names
