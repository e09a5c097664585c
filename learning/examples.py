"""A training example of the learner: a labelled row and how it was obtained.

Its own module so that the learner's state (``learning.state``, which keeps the examples) and the answers
(``learning.answers``, whose ``Change`` records the example an answer added) both name it without naming
each other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SOURCES = ("label", "demo")  # how a training example may have been obtained


@dataclass(frozen=True)
class Example:
    """One labelled instance (a read-only row) and how it was obtained ("demo" or "label")."""

    x: np.ndarray
    concept: str
    source: str
    scene_id: int
