"""Rule-based arbitration HFS+P and HFS+A: the feature-subset query first, then a baseline (thesis §6.4.2).

The teacher's answer (human feature selection, HFS) restricts every classifier
to the chosen features; after it, HFS+P asks only for demonstrations and
HFS+A only label queries by uncertainty. If the feature query is not
affordable the baseline starts at once.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision, FeatureQuery
from learning.state import LearningState
from learning.strategies.active import ActiveStrategy
from learning.strategies.base import Strategy
from learning.strategies.passive import PassiveStrategy

FEATURES_FIRST = "First I ask which features matter, so that every example after it counts for more."


def feature_query_first(state: LearningState) -> Decision | None:
    """The feature-subset query if it has not been asked and the budget covers it."""
    if not state.feature_query_asked and state.can_afford(FeatureQuery()):
        return Decision(FeatureQuery(), FEATURES_FIRST)
    return None


class HfsPassiveStrategy(Strategy):
    name = "hfs-passive"

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        return feature_query_first(state) or PassiveStrategy().choose(state, rng)


class HfsActiveStrategy(Strategy):
    name = "hfs-active"

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        return feature_query_first(state) or ActiveStrategy().choose(state, rng)
