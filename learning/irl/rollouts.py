"""Trajectory-level maximum-entropy IRL by feature matching with rollouts (thesis eq. 7.6, 7.7).

The gradient of the MaxEnt objective is the expert's feature counts minus the
learner's expected feature counts,

    grad_w L = E_expert[phi_E(tau)] - sum_tau p(tau | w) phi_L(tau)      (eq. 7.7)

where a trajectory's counts are the sum over its turns of the features of the
chosen action (thesis §2.5.2). The expectation is estimated from episodes the
learner plays itself with the MaxEnt policy P(a|s) ~ exp(w . Phi[a]): the
caller supplies that as a ``rollout(weights, rng) -> QuestioningEpisode``
function (the dialog loop with a scripted teacher, or a synthetic
environment), and picks each action with ``learning.irl.policy.sample_choice``. Unlike the
per-turn fit in ``learning.irl.maxent`` this sees the states the learner's own
choices lead to, at the price of simulating episodes every iteration.
Counts are divided by the number of turns, so episodes of any length mix.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from learning.irl.demonstrations import QuestioningEpisode
from learning.irl.maxent import (
    AdamAscent,
    IrlResult,
    IterationRecord,
    PaddedTurns,
    compute_threads,
    feature_scale,
    log_likelihood,
    make_result,
)

Rollout = Callable[[np.ndarray, np.random.Generator], QuestioningEpisode]


@dataclass(frozen=True)
class FeatureMatchingConfig:
    """Stochastic gradient ascent on eq. 7.7 with Adam; rollouts estimate the learner's counts."""

    max_iterations: int = 100  # thesis §7.4.1
    rollouts_per_iteration: int = 4
    learning_rate: float = 0.3
    l2: float = 1e-3
    standardize: bool = True
    seed: int = 0
    threads: int = 1  # torch and BLAS threads during the fit, rollouts included

    def __post_init__(self) -> None:
        for name in ("max_iterations", "rollouts_per_iteration"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        for name in ("learning_rate", "l2"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value) or value < 0:
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if isinstance(self.threads, bool) or not isinstance(self.threads, int) or self.threads < 1:
            raise ValueError(f"threads must be an integer >= 1, got {self.threads!r}")
        if self.learning_rate == 0:
            raise ValueError("learning_rate must be > 0")


def mean_feature_counts(episodes: Sequence[QuestioningEpisode]) -> np.ndarray:
    """Mean over episodes of phi(tau) / |tau|: the per-turn feature counts of eq. 7.6."""
    return np.mean([episode.feature_counts() / len(episode.turns) for episode in episodes], axis=0)


def fit_feature_matching(expert: Sequence[QuestioningEpisode], rollout: Rollout,
                         validation: Sequence[QuestioningEpisode] | None = None,
                         config: FeatureMatchingConfig | None = None,
                         initial_weights: np.ndarray | None = None) -> IrlResult:
    """Learn w so that the learner's rollouts match the expert's feature counts (eq. 7.6, 7.7).

    Each iteration plays ``rollouts_per_iteration`` episodes with the current
    weights. The kept weights are those whose greedy choices agree best with
    the validation episodes (without them: with the expert episodes); ties go
    to the higher log-likelihood, then to the earlier iteration.
    """
    config = config or FeatureMatchingConfig()
    with compute_threads(config.threads):
        return _fit_feature_matching(expert, rollout, validation, config, initial_weights)


def _fit_feature_matching(expert, rollout: Rollout, validation, config: FeatureMatchingConfig,
                          initial_weights) -> IrlResult:
    started = time.perf_counter()
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    train_turns = PaddedTurns(expert, "expert episodes")
    names = train_turns.feature_names
    validation_turns = PaddedTurns(validation, "validation episodes") if validation else None
    if validation_turns is not None and validation_turns.feature_names != names:
        raise ValueError(f"validation episodes have features {list(validation_turns.feature_names)}, expert "
                         f"episodes {list(names)}; they must match")
    scale, identifiable = feature_scale(train_turns, config.standardize)
    expert_counts = mean_feature_counts(expert) / scale
    w0 = np.zeros(len(names)) if initial_weights is None else np.asarray(initial_weights, dtype=np.float64)
    if w0.shape != (len(names),) or not np.all(np.isfinite(w0)):
        raise ValueError(f"initial_weights must be {len(names)} finite numbers, got shape {w0.shape}")
    adam, x = AdamAscent(config.learning_rate), w0 * scale

    def score(w: np.ndarray) -> tuple[float, float | None, tuple]:
        train_agreement = train_turns.agreement(w)
        if validation_turns is None:
            return train_agreement, None, (train_agreement, log_likelihood(train_turns, w))
        validation_agreement = validation_turns.agreement(w)
        return train_agreement, validation_agreement, (validation_agreement, log_likelihood(validation_turns, w))

    best_w = w0.copy()
    train_agreement, validation_agreement, best_key = score(best_w)
    history, best_iteration = [IterationRecord(0, float("nan"), train_agreement, validation_agreement)], 0
    for iteration in range(1, config.max_iterations + 1):
        episodes = [_checked(rollout(x / scale, rng), names) for _ in range(config.rollouts_per_iteration)]
        gap = expert_counts - mean_feature_counts(episodes) / scale  # eq. 7.7 in standardised units
        x = adam.step(x, (gap - config.l2 * x) * identifiable)
        w = x / scale
        train_agreement, validation_agreement, key = score(w)
        history.append(IterationRecord(iteration, float(np.linalg.norm(gap)), train_agreement, validation_agreement))
        if key > best_key:
            best_key, best_w, best_iteration = key, w, iteration
    settings = {"method": "maxent-irl-feature-matching", "optimizer": "adam", "l2": float(config.l2),
                "rollouts_per_iteration": config.rollouts_per_iteration}
    return make_result(names, best_w, identifiable, history, best_iteration, config.max_iterations, False, settings,
                       train_turns, validation_turns, started)


def _checked(episode, names: tuple[str, ...]) -> QuestioningEpisode:
    if not isinstance(episode, QuestioningEpisode):
        raise ValueError(f"the rollout function must return a QuestioningEpisode, got {type(episode).__name__}")
    if episode.feature_names != names:
        raise ValueError(f"a rollout episode has features {list(episode.feature_names)}, the expert's are "
                         f"{list(names)}; they must match")
    return episode
