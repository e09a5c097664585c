"""Random arbitration R: any affordable query, uniformly at random (thesis §6.4.2).

The candidates are a demonstration query per concept, a label query per scene
object not yet labelled in this scene, and the feature-subset query until it
has been asked. R never chooses to stay quiet while it can afford a query.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision
from learning.decision.candidates import candidate_actions
from learning.state import LearningState
from learning.strategies.base import Strategy

KIND_WORDS = {"label": "label", "demo": "demonstration", "feature": "feature-subset"}


class RandomStrategy(Strategy):
    name = "random"

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        queries = candidate_actions(state)[:-1]  # the last candidate is always NoQuery
        if not queries:
            return self.nothing_affordable(state)
        action = queries[int(rng.integers(len(queries)))]
        return Decision(action, f"I picked a {KIND_WORDS[action.kind]} query at random among "
                                f"{len(queries)} questions I can afford.")
