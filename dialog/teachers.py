"""Teachers answer the robot's questions; all share one small interface."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from bullet_world import Scene
from learning.actions import Action


@dataclass(frozen=True)
class Answer:
    """What the teacher said (``raw``) and what it means (``value``; None = no usable answer).

    label query: a concept name; demonstration: an object index (None: none in
    the scene); feature query: a tuple of feature indices.
    """

    raw: str
    value: object = None


class Teacher(Protocol):
    def answer(self, action: Action, question: str, scene: Scene) -> Answer: ...


class OracleTeacher:
    """A scripted teacher that answers from the scene's hidden ground truth."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng

    def answer(self, action: Action, question: str, scene: Scene) -> Answer:
        if action.kind == "label":
            concept = scene.truth.concepts[action.object_index]
            return Answer(f"a {concept}", concept)
        if action.kind == "demo":
            members = [i for i, c in enumerate(scene.truth.concepts) if c == action.concept]
            if not members:
                return Answer(f"there is no {action.concept} here", None)
            index = int(members[self.rng.integers(len(members))])
            return Answer(f"number {index + 1}", index)
        raise ValueError(f"the oracle teacher cannot answer a '{action.kind}' question yet")
