"""A synthetic questioning task with the structure of thesis ch. 7, for testing and measuring IRL.

It has no concept models: it draws, from a seeded generator, how much each
candidate action is expected to move the four learning features, and keeps
the environment features exactly as DT-task-env defines them, so demonstrations
by a policy with known weights have the shape of real ones (thesis §7.3.1):

- candidates each turn: a label query per scene object (cost 1), a demo query
  per concept (cost 2), the feature-subset query until asked (cost 2), no query
  (cost 0); only affordable queries are offered, so once the budget is spent
  no query is the only candidate;
- every candidate, no query included, is scored at its next state (eq. 7.1):
  budget consumption (spent + cost) / B; remaining time (T - t - 1) / T, equal
  on every candidate of a turn (time passes whatever is asked); non-query time,
  the fraction of no-query turns in a window of ``change_every`` turns ending
  with this one; no query keeps the learning features;
- a scene change every ``change_every`` turns lowers the learning features
  (the models meet objects in a new state), as in the training condition.

The chosen action's expected features plus a little outcome noise become the
next state. Every random choice goes through the ``numpy.random.Generator``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from learning.actions import DEFAULT_COSTS, ActionKind
from learning.irl.demonstrations import DecisionTurn, QuestioningEpisode, turn_with_no_query
from learning.irl.policy import greedy_choice, sample_choice

DT_TASK_ENV_FEATURES: tuple[str, ...] = (
    "classifier_discriminability", "class_distribution_uniformity", "instance_variation", "prediction_margin",
    "budget_consumption", "remaining_time", "non_query_time",
)
LEARNING, BUDGET, TIME, NON_QUERY = slice(0, 4), 4, 5, 6
# mean and spread of the expected change of the four learning features, per query kind
EXPECTED_GAIN = {"label": (0.015, 0.03), "demo": (0.04, 0.03), "feature": (0.10, 0.03)}

Policy = Callable[[DecisionTurn, np.random.Generator], int]


@dataclass(frozen=True)
class SyntheticQuestioningTask:
    """The training condition of thesis §7.4.1 by default: budget 15, 30 turns, a change every 10 turns."""

    budget: float = 15.0
    turns: int = 30
    change_every: int = 10
    concepts: int = 4
    objects: tuple[int, int] = (5, 55)  # scene size drawn per scene, inclusive: 10-60 candidates a turn
    outcome_noise: float = 0.01

    def episode(self, policy: Policy, rng: np.random.Generator, name: str = "") -> QuestioningEpisode:
        """Play one episode, ``policy(turn, rng)`` choosing each turn's action index."""
        learning = rng.uniform(0.1, 0.3, 4)
        spent, feature_query_asked = 0.0, False
        history: list[str] = []
        turns: list[DecisionTurn] = []
        for t in range(self.turns):
            if t % self.change_every == 0:
                learning = np.clip(learning - rng.uniform(0.05, 0.15, 4), 0.0, 1.0) if t else learning
                n_objects = int(rng.integers(self.objects[0], self.objects[1] + 1))
            quiet = np.empty(len(DT_TASK_ENV_FEATURES))  # the next state after a quiet turn
            quiet[LEARNING] = learning
            quiet[BUDGET] = spent / self.budget
            quiet[TIME] = (self.turns - t - 1) / self.turns
            quiet[NON_QUERY] = self._non_query_time(history + ["none"])
            offered: list[ActionKind] = ["label"] * n_objects
            offered += ["demo"] * self.concepts
            if not feature_query_asked:
                offered.append("feature")
            kinds = [kind for kind in offered if spent + DEFAULT_COSTS[kind] <= self.budget]
            rows = np.tile(quiet, (len(kinds), 1))
            for row, kind in zip(rows, kinds):
                mean, spread = EXPECTED_GAIN[kind]
                row[LEARNING] = np.clip(learning + rng.normal(mean, spread, 4) * (1.0 - learning), 0.0, 1.0)
                row[BUDGET] = (spent + DEFAULT_COSTS[kind]) / self.budget
                row[NON_QUERY] = self._non_query_time(history + ["query"])
            turn = turn_with_no_query(quiet, rows, None, kinds)
            choice = policy(turn, rng)
            turn = DecisionTurn(turn.phi, choice, turn.kinds)
            turns.append(turn)
            kind = kinds[choice] if choice < len(kinds) else "none"  # no query is the last candidate
            if kind != "none":
                learning = np.clip(turn.phi[choice, LEARNING] + rng.normal(0, self.outcome_noise, 4), 0.0, 1.0)
                spent += DEFAULT_COSTS[kind]
                feature_query_asked |= kind == "feature"
            history.append("none" if kind == "none" else "query")
        metadata = {"source": "synthetic", "budget": self.budget, "turns": self.turns,
                    "change_every": self.change_every}
        return QuestioningEpisode(DT_TASK_ENV_FEATURES, tuple(turns), name, metadata)

    def _non_query_time(self, history: list[str]) -> float:
        window = history[-self.change_every:]
        return sum(kind == "none" for kind in window) / self.change_every


def greedy_policy(weights: np.ndarray) -> Policy:
    """The DT learner with known weights: argmax_a w . Phi[a], ties to no query (thesis eq. 7.1)."""
    return lambda turn, rng: greedy_choice(turn, weights)


def softmax_policy(weights: np.ndarray) -> Policy:
    """A noisy expert: P(a|s) ~ exp(w . Phi[a]) (the MaxEnt policy, thesis eq. 7.5)."""
    return lambda turn, rng: sample_choice(turn.phi, weights, rng)
