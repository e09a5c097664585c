"""The one interface every questioning strategy implements."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from learning.actions import Decision, NoQuery
from learning.state import LearningState


class Strategy(ABC):
    """Looks at the learning state and returns one action with a reason.

    The contract (``learning.check_strategy`` checks it): ``choose`` returns a :class:`Decision` with a one-sentence
    explanation, asks only what the state admits and the budget covers (else ``NoQuery``), only reads the state,
    and draws random numbers only from ``rng``. A subclass of your own runs as ``--strategy module.path:ClassName``.
    """

    name: str = ""
    # None: the learner's models use every feature (or the teacher's answer); "FI", "ES" or "ER": where the teacher
    # named none, the subset that chapter 5's method selects from the examples so far (LearningState)
    feature_selection: str | None = None

    @abstractmethod
    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        """The action for this turn; it must be affordable."""

    @staticmethod
    def out_of_budget(state: LearningState) -> Decision:
        return Decision(NoQuery(), f"Nothing to ask: my question budget is spent ({state.spent:g} of "
                                   f"{state.budget:g}).")

    @classmethod
    def nothing_affordable(cls, state: LearningState) -> Decision:
        """No query left to ask: the budget is short, or every object in the scene is already labelled."""
        if state.remaining_budget < min(state.costs[k] for k in ("label", "demo", "feature")) - 1e-9:
            return cls.out_of_budget(state)
        return Decision(NoQuery(), "Nothing to ask: I already know every object in this scene and can't "
                                   "afford anything else.")
