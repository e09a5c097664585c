"""The setup every strategy that reads the turn's candidates shares: one place for it.

DT (``decision_theoretic``), the scripted expert (``scripted_expert``) and the MaxEnt policy of the
IRL rollouts (``maxent_policy``) all start a turn the same way: the candidates with their expected
decision features E[phi(s') | a] (``learning.decision.candidates.expected_decision_features``, eq. 6.3,
7.1), recorded as ``last_candidates`` for IRL, and "nothing affordable" when only no query is left.
"""

from __future__ import annotations

from learning.actions import Decision
from learning.decision.candidates import CandidateFeatures, expected_decision_features
from learning.state import LearningState
from learning.strategies.base import Strategy
from learning.whatif import WhatIfEngine


class CandidateStrategy(Strategy):
    """A strategy that chooses from the candidates table; subclasses set ``engine`` and ``window_factor``."""

    engine: WhatIfEngine  # as learning.whatif.make_engine makes it
    window_factor: float
    last_candidates: CandidateFeatures | None = None  # what the last choice saw (for IRL recording)

    def candidates(self, state: LearningState, seconds: bool = True,
                   habits: bool = False) -> tuple[CandidateFeatures, Decision | None]:
        """This turn's candidates, recorded as ``last_candidates``, and the decision when there is no choice.

        The decision is ``nothing_affordable`` when no query is the only candidate (else None: choose).
        ``seconds`` False ignores embodied costs (time in turns) even when the episode has them; ``habits`` adds
        the expert-habit features (``learning.decision.habits``).
        """
        candidates = expected_decision_features(state, self.engine, self.window_factor, seconds=seconds,
                                                habits=habits)
        self.last_candidates = candidates
        if len(candidates.actions) == 1:
            return candidates, self.nothing_affordable(state)
        return candidates, None
