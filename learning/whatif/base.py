"""The what-if interface: scene probabilities after every simulated answer (thesis eq. 6.3, 7.1).

An engine answers one question for a learning state: if the teacher answered
this query that way, what would p(y|x) over the current scene become?

* a demonstration of concept y that turns out to be scene object x, and
* the label y for scene object x

both add <x, y> to every concept's training set, so they lead to the same
state. The feature-subset query's answers are the per-concept computational
subsets F_{y,c}: answer y switches every classifier to F_{y,c}.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import numpy as np

from learning.features.selection import computational_subsets

FEATURE_SELECTION_METHOD = "ES"  # the thesis's F_{y,c}: CFS-merit forward selection (§5.3.1)
# The DT's guess of the teacher's answer needs a subset after a handful of examples; chapter 5's chance test
# at 0.05 leaves most concepts with every feature until about 20 examples, so the guess uses a looser one.
FEATURE_SELECTION_SIGNIFICANCE = 0.5


@dataclass(frozen=True)
class Outcomes:
    """Scene probabilities of every simulated next state; the last two axes are (scene objects, concepts).

    demo[y, x]: the teacher shows scene object x for DemoQuery(concept y), shape (|Y|, |X|, |X|, |Y|).
    label[k, y]: the teacher says concept y for LabelQuery(label_objects[k]), shape (k, |Y|, |X|, |Y|).
    feature[y]: the teacher gives F_{y,c}, shape (|Y|, |X|, |Y|), or None when not simulated.
    """

    demo: np.ndarray
    label: np.ndarray
    feature: np.ndarray | None
    label_objects: tuple[int, ...]
    shared: bool = False  # label[k, y] is demo[y, label_objects[k]] by construction (one table for both)


class WhatIfEngine(ABC):
    """Simulates every (query, answer) pair of one turn."""

    name: str = ""

    @abstractmethod
    def simulate(self, state, label_objects: Sequence[int], feature_query: bool) -> Outcomes:
        """Outcomes for every demo query, the label queries on ``label_objects`` and, if asked for, the FSQ."""


def feature_query_subsets(state, method: str = FEATURE_SELECTION_METHOD,
                          significance: float = FEATURE_SELECTION_SIGNIFICANCE) -> dict[Hashable, np.ndarray]:
    """F_{y,c} for every concept from the raw training set (rank-based, so the scaling does not matter).

    One-vs-rest per concept (``computational_subsets``); a concept without positive or negative examples
    gets every feature.
    """
    X, labels = state.training_matrix()
    if len(X) == 0:
        return {c: np.arange(len(state.feature_names)) for c in state.concepts}
    return computational_subsets(X, labels, state.concepts, method=method, significance=significance)


def cached(state, key: str, version: Hashable, compute):
    """``compute()`` once per ``version`` of ``state`` (any comparable tag; kept in ``state.cache``)."""
    entry = state.cache.get(key)
    if entry is not None and entry[0] == version:
        return entry[1]
    value = compute()
    state.cache[key] = (version, value)
    return value
