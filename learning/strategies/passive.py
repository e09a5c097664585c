"""Passive baseline P: only demonstration queries (thesis §6.4.1).

Simulates stratified sampling: ask for the concept with the fewest examples so
far, breaking ties at random, so that the class distribution stays uniform. A
concept the teacher could not show in this scene is not asked for again until
the scene changes.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision, DemoQuery, NoQuery
from learning.state import LearningState
from learning.strategies.base import Strategy


class PassiveStrategy(Strategy):
    name = "passive"

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        counts = {c: n for c, n in state.counts_per_concept().items() if c not in state.absent_in_scene}
        if not counts:
            return Decision(NoQuery(), "Nothing to ask: none of the concepts can be shown in this scene.")
        fewest = min(counts.values())
        candidates = [c for c in counts if counts[c] == fewest]
        concept = candidates[int(rng.integers(len(candidates)))]
        action = DemoQuery(concept)
        if not state.can_afford(action):
            return self.out_of_budget(state)
        return Decision(action, f"I have seen the fewest examples of {concept} ({fewest}), so I ask for one.")


class PassiveFeatureSelectingStrategy(PassiveStrategy):
    """The thesis's P (figs. 6.4, 6.5): P whose learner selects features computationally (ES, the F_{y,c} of
    §6.4.2 the what-if engines assume too; docs/strategies.md says why), since a baseline never asks for them."""

    name = "passive-fs"
    feature_selection = "ES"
