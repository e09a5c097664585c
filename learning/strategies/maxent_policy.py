"""The MaxEnt policy as a strategy: actions sampled from P(a|s) ~ exp(w . Phi[a]) (thesis eq. 7.5, 7.7).

IRL's learner plays its rollouts with this strategy. Each turn it computes the
candidates and E[phi(s') | a] exactly as the DT strategy does
(``CandidateStrategy.candidates``, learning/strategies/candidate_based.py), draws one
action from the MaxEnt policy with its own ``numpy.random.Generator``, and
records the turn as an IRL ``DecisionTurn``, so the rollout's feature counts
are comparable with those of the expert's demonstrations.
"""

from __future__ import annotations

import numpy as np

from learning.actions import Decision
from learning.decision.features import FEATURE_NAMES
from learning.decision.habits import EXTENDED_FEATURE_NAMES
from learning.irl.demonstrations import DecisionTurn, QuestioningEpisode
from learning.irl.policy import policy_probabilities
from learning.state import LearningState
from learning.strategies.candidate_based import CandidateStrategy
from learning.whatif import make_engine


class MaxEntPolicyStrategy(CandidateStrategy):
    """Samples each turn's action from the MaxEnt policy with weights ``weights`` (FEATURE_NAMES order, or
    EXTENDED_FEATURE_NAMES order to weigh the expert-habit features too)."""

    name = "maxent-policy"

    def __init__(self, weights, rng: np.random.Generator, engine="fast", window_factor: float = 1.0):
        weights = np.asarray(weights, dtype=np.float64)
        if weights.shape not in ((len(FEATURE_NAMES),), (len(EXTENDED_FEATURE_NAMES),)) \
                or not np.all(np.isfinite(weights)):
            raise ValueError(f"the MaxEnt policy needs {len(FEATURE_NAMES)} finite weights ({', '.join(FEATURE_NAMES)})"
                             f" or {len(EXTENDED_FEATURE_NAMES)} with the habit features, got shape {weights.shape}")
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"the MaxEnt policy samples with a numpy Generator, got {type(rng).__name__}")
        self.weights, self.rng = weights, rng
        self.engine = make_engine(engine)
        self.window_factor = window_factor
        self.feature_names = FEATURE_NAMES if len(weights) == len(FEATURE_NAMES) else EXTENDED_FEATURE_NAMES
        self.turns: list[DecisionTurn] = []

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        """One action drawn from P(a|s, w); the episode's generator ``rng`` is left alone (the strategy has its own)."""
        candidates, nothing = self.candidates(state, habits=self.feature_names is EXTENDED_FEATURE_NAMES)
        if nothing is not None:
            index, decision = 0, nothing
        else:
            probabilities = policy_probabilities(candidates.expected, self.weights)
            index = int(self.rng.choice(len(probabilities), p=probabilities))
            decision = Decision(candidates.actions[index], f"Sampled from the MaxEnt policy (p = "
                                                           f"{probabilities[index]:.3f}).")
        self.turns.append(DecisionTurn(candidates.expected, index, candidates.kinds))
        return decision

    def episode(self, name: str = "", metadata: dict | None = None) -> QuestioningEpisode:
        """The turns played so far as an IRL episode (what the rollout contributes to eq. 7.7)."""
        return QuestioningEpisode(self.feature_names, tuple(self.turns), name, metadata or {})
