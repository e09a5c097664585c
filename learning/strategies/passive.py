"""Passive baseline P: only demonstration queries (thesis §6.4.1).

Simulates stratified sampling: ask for the concept with the fewest examples so
far, breaking ties at random, so that the class distribution stays uniform.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision, DemoQuery
from learning.state import LearningState
from learning.strategies.base import Strategy


class PassiveStrategy(Strategy):
    name = "passive"

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        counts = state.counts_per_concept()
        fewest = min(counts.values())
        candidates = [c for c in state.concepts if counts[c] == fewest]
        concept = candidates[int(rng.integers(len(candidates)))]
        action = DemoQuery(concept)
        if not state.can_afford(action):
            return self.out_of_budget(state)
        return Decision(action, f"I have seen the fewest examples of {concept} ({fewest}), so I ask for one.")
