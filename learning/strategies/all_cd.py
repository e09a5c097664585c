"""Rule-based arbitration All/CD, HFS + P + A (thesis §6.4.2).

1. The feature-subset query (once).
2. A minimal set of demonstrations that keeps the classes uniform: ask for
   the concept with the fewest examples until every concept has
   ``examples_per_concept`` (2: the thesis's rule-based strategies used 8
   demonstrations for 4 concepts). Label answers count towards it too; a
   concept the teacher could not show in this scene waits for the next scene.
3. Label queries by uncertainty (eq. 6.1) for the rest of the episode.

Each step that cannot be afforded is skipped.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision, DemoQuery
from learning.state import LearningState
from learning.strategies.active import ActiveStrategy
from learning.strategies.base import Strategy
from learning.strategies.hfs import feature_query_first


class AllClassDistributionStrategy(Strategy):
    name = "all-cd"

    def __init__(self, examples_per_concept: int = 2):
        if isinstance(examples_per_concept, bool) or not isinstance(examples_per_concept, int) \
                or examples_per_concept < 0:
            raise ValueError(f"examples_per_concept must be a whole number >= 0, got {examples_per_concept!r}")
        self.examples_per_concept = examples_per_concept

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        first = feature_query_first(state)
        if first is not None:
            return first
        counts = {c: n for c, n in state.counts_per_concept().items() if c not in state.absent_in_scene}
        fewest = min(counts.values(), default=self.examples_per_concept)
        if fewest < self.examples_per_concept and len(state.scene_X):
            concept = next(c for c in counts if counts[c] == fewest)  # ties: task order
            action = DemoQuery(concept)
            if state.can_afford(action):
                return Decision(action, f"I have only {fewest} example{'s' if fewest != 1 else ''} of {concept}; "
                                        f"a demonstration keeps the classes balanced.")
        return ActiveStrategy().choose(state, rng)
