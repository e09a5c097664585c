"""The one interface every questioning strategy implements."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from learning.actions import Decision, NoQuery
from learning.state import LearningState


class Strategy(ABC):
    """Looks at the learning state and returns one action with a reason."""

    name: str = ""

    @abstractmethod
    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        """The action for this turn; it must be affordable."""

    @staticmethod
    def out_of_budget(state: LearningState) -> Decision:
        return Decision(NoQuery(), f"Nothing to ask: my question budget is spent ({state.spent:g} of "
                                   f"{state.budget:g}).")
