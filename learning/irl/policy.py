"""How a weight vector chooses among a turn's candidates: the DT rule and the MaxEnt policy (thesis eq. 7.1, 7.5).

numpy only, so strategies and synthetic tasks can use it without importing torch.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from learning.decision.resolution import EU_RESOLUTION
from learning.irl.demonstrations import DecisionTurn, QuestioningEpisode


def greedy_choice(turn: DecisionTurn, weights: np.ndarray, rtol: float = EU_RESOLUTION) -> int:
    """The DT learner's action: argmax_a w . Phi[a]; a tie with no query goes to no query, else to the first."""
    utilities = turn.utilities(weights)
    best = float(utilities.max())
    tied = np.flatnonzero(utilities >= best - rtol * max(1.0, abs(best)))
    no_query = turn.no_query_index
    if no_query is not None and no_query in tied:
        return no_query
    return int(tied[0])


def agreement(episodes: Sequence[QuestioningEpisode], weights: np.ndarray) -> float:
    """Fraction of turns with a real choice (>= 2 candidates) on which argmax_a w . Phi[a] is the expert's action."""
    hits, counted = 0, 0
    for episode in episodes:
        for turn in episode.turns:
            if turn.n_actions < 2:
                continue
            counted += 1
            hits += greedy_choice(turn, weights) == turn.chosen
    if counted == 0:
        raise ValueError("no turn offers a choice (every turn has a single candidate action); agreement is undefined")
    return hits / counted


def policy_probabilities(phi: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """P(a | s, w) proportional to exp(w . Phi[a]) for one turn's candidates (the MaxEnt policy)."""
    utilities = np.asarray(phi, dtype=np.float64) @ np.asarray(weights, dtype=np.float64)
    utilities = utilities - utilities.max()
    probabilities = np.exp(utilities)
    return probabilities / probabilities.sum()


def sample_choice(phi: np.ndarray, weights: np.ndarray, rng: np.random.Generator) -> int:
    """Draw one action from P(a | s, w): a noisy expert's move, or the learner's inside a rollout."""
    probabilities = policy_probabilities(phi, weights)
    return int(rng.choice(len(probabilities), p=probabilities))
