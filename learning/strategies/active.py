"""Active baseline A: label queries by uncertainty sampling (thesis §6.4.1, eq. 6.1).

Asks for the label of the scene object whose concept distribution has the
highest entropy, skipping objects already asked about in this scene.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision, LabelQuery, NoQuery
from learning.concepts import entropy, normalise_rows
from learning.state import LearningState
from learning.strategies.base import Strategy


class ActiveStrategy(Strategy):
    name = "active"

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        if not state.can_afford(LabelQuery(0)):
            return self.out_of_budget(state)
        P = state.probabilities()
        scores = entropy(P)
        for index in state.labelled_in_scene:
            scores[index] = -np.inf
        if len(scores) == 0 or not np.isfinite(scores.max()):
            return Decision(NoQuery(), "Nothing to ask: I already asked about every object in this scene.")
        index = int(np.argmax(scores))
        top = np.argsort(normalise_rows(P)[index])[::-1][:2]
        first, second = (state.concepts[i] for i in top)
        return Decision(LabelQuery(index), f"I can't tell {first} from {second} for object {index + 1}.")


class ActiveFeatureSelectingStrategy(ActiveStrategy):
    """The thesis's A and U-sampling (figs. 6.4, 6.5, 7.x): uncertainty sampling whose learner selects features
    computationally (ES, as :class:`~learning.strategies.passive.PassiveFeatureSelectingStrategy`)."""

    name = "active-fs"
    feature_selection = "ES"
