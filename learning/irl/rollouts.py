"""Trajectory-level maximum-entropy IRL by feature matching with rollouts (thesis eq. 7.6, 7.7).

The gradient of the MaxEnt objective is the expert's feature counts minus the
learner's expected feature counts,

    grad_w L = E_expert[phi_E(tau)] - sum_tau p(tau | w) phi_L(tau)      (eq. 7.7)

where a trajectory's counts are the sum over its turns of the features of the
chosen action (thesis §2.5.2). The expectation is estimated from episodes the
learner plays itself with the MaxEnt policy P(a|s) ~ exp(w . Phi[a]): the
caller supplies them as ``rollouts(weights, iteration, count)`` (the dialog
loop with a scripted teacher, dialog.experiments.irl_rollouts, possibly in
parallel; or ``serial_rollouts`` around a synthetic environment), each action
drawn from that policy with a generator seeded by (seed, iteration, rollout). Unlike the
per-turn fit in ``learning.irl.maxent`` this sees the states the learner's own
choices lead to, at the price of simulating episodes every iteration.
Counts are divided by the number of turns, so episodes of any length mix.

The ascent starts (``start="per-turn"``, the default since issue 15) from the per-turn MaxEnt fit of the
same expert episodes (``fit_maxent_irl`` with the softmax policy: eq. 7.5 maximised as the
log-likelihood of the expert's choices, which the thesis states L_ME is equal to); that start is
iteration 0 and a candidate for the kept iterate. ``start="zero"`` begins at w = 0 (the earlier default).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import torch

from learning.irl.demonstrations import QuestioningEpisode
from learning.irl.maxent import (
    AdamAscent,
    IrlConfig,
    IrlResult,
    IterationRecord,
    PaddedTurns,
    compute_threads,
    feature_scale,
    fit_maxent_irl,
    log_likelihood,
    make_result,
)
from learning.irl.policy import policy_probabilities

Rollout = Callable[[np.ndarray, np.random.Generator], QuestioningEpisode]  # one episode with weights w
# (weights, iteration, count) -> that iteration's ``count`` episodes; the caller may play them in parallel
RolloutBatch = Callable[[np.ndarray, int, int], Sequence[QuestioningEpisode]]
Evaluate = Callable[[np.ndarray], float]  # a score of weights on held-out episodes, higher is better
Progress = Callable[[IterationRecord, float], None]  # (this iteration's record, seconds since the start)


STARTS = ("per-turn", "zero")
# which iterate is kept: the best held-out agreement of greedy choices with the expert's (ties: likelihood), the
# best held-out log-likelihood of the expert's choices (eq. 7.5, the IRL objective; ties: agreement), or the best
# task accuracy of greedy episodes on validation seeds (needs ``evaluate``; the CLI's criterion before issue 27)
SELECTIONS = ("agreement", "log_likelihood", "accuracy")  # the first two as IrlConfig.select_by


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
    evaluate_every: int = 1  # with ``evaluate``: score every k-th iterate (and the last)
    optimizer: str = "adam"  # or "gradient": plain ascent along the gap, x += learning_rate * gap
    expected_counts: bool = True  # learner's counts: the policy's expectation at each visited state (else sampled)
    start: str = "per-turn"  # iteration 0: the per-turn MaxEnt fit of the expert episodes, or "zero" (w = 0)
    select: str = "agreement"  # SELECTIONS; "accuracy" needs ``evaluate``

    def __post_init__(self) -> None:
        for name in ("max_iterations", "rollouts_per_iteration", "evaluate_every"):
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
        if self.start not in STARTS:
            raise ValueError(f"start must be one of {', '.join(STARTS)}, got {self.start!r}")
        if self.select not in SELECTIONS:
            raise ValueError(f"select must be one of {', '.join(SELECTIONS)}, got {self.select!r}")


def rollout_generator(seed: int, iteration: int, index: int) -> np.random.Generator:
    """The policy's generator for rollout ``index`` of ``iteration``: the same numbers wherever it runs."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(iteration), int(index)]))


def serial_rollouts(rollout: Rollout, seed: int = 0) -> RolloutBatch:
    """A batch of rollouts played one after another here, each with its own seeded generator."""
    def batch(weights: np.ndarray, iteration: int, count: int) -> list[QuestioningEpisode]:
        return [rollout(weights, rollout_generator(seed, iteration, index)) for index in range(count)]
    return batch


def mean_feature_counts(episodes: Sequence[QuestioningEpisode]) -> np.ndarray:
    """Mean over episodes of phi(tau) / |tau|: the per-turn feature counts of eq. 7.6."""
    return np.mean([episode.feature_counts() / len(episode.turns) for episode in episodes], axis=0)


def mean_expected_feature_counts(episodes: Sequence[QuestioningEpisode], weights: np.ndarray) -> np.ndarray:
    """Like ``mean_feature_counts``, but each turn counts sum_a P(a|s_t, w) Phi_t[a] instead of the sampled row.

    The same expectation as the sampled counts (the policy's choice averaged out at every state the
    rollout visited), with less variance: the estimate of eq. 7.7's learner term when the rollouts
    were played with ``weights``.
    """
    per_episode = [np.sum([policy_probabilities(turn.phi, weights) @ turn.phi for turn in episode.turns], axis=0)
                   / len(episode.turns) for episode in episodes]
    return np.mean(per_episode, axis=0)


def fit_feature_matching(expert: Sequence[QuestioningEpisode], rollouts: RolloutBatch,
                         validation: Sequence[QuestioningEpisode] | None = None,
                         config: FeatureMatchingConfig | None = None,
                         initial_weights: np.ndarray | None = None, evaluate: Evaluate | None = None,
                         progress: Progress | None = None) -> IrlResult:
    """Learn w so that the learner's rollouts match the expert's feature counts (eq. 7.6, 7.7).

    Iteration 0 is ``initial_weights`` if given, else the per-turn MaxEnt fit of ``expert``
    (with ``validation`` choosing its iterate; ``config.start="per-turn"``) or w = 0
    (``start="zero"``). Each iteration plays ``rollouts_per_iteration`` episodes with the current
    weights (``rollouts(w, iteration, count)``). Which iterate is kept (``config.select``), always on
    the validation episodes (without them: the expert episodes), ties to the earlier iteration:
    "agreement" (the default), the greedy choices' agreement with the expert's, ties to the higher
    log-likelihood; "log_likelihood", the mean log-likelihood of the expert's choices (eq. 7.5), ties to
    the higher agreement; "accuracy", the evaluated iterate with the best ``evaluate(w)`` (the task
    accuracy on validation episodes), ties to the higher agreement. Under the first two, ``evaluate``,
    if given, scores only the kept iterate.
    """
    config = config or FeatureMatchingConfig()
    if config.select == "accuracy" and evaluate is None:
        raise ValueError("select='accuracy' scores iterates by task accuracy: pass evaluate(w)")
    with compute_threads(config.threads):
        return _fit_feature_matching(expert, rollouts, validation, config, initial_weights, evaluate, progress)


def _fit_feature_matching(expert, rollouts: RolloutBatch, validation, config: FeatureMatchingConfig,
                          initial_weights, evaluate: Evaluate | None, progress: Progress | None) -> IrlResult:
    started = time.perf_counter()
    torch.manual_seed(config.seed)
    train_turns = PaddedTurns(expert, "expert episodes")
    names = train_turns.feature_names
    validation_turns = PaddedTurns(validation, "validation episodes") if validation else None
    if validation_turns is not None and validation_turns.feature_names != names:
        raise ValueError(f"validation episodes have features {list(validation_turns.feature_names)}, expert "
                         f"episodes {list(names)}; they must match")
    scale, identifiable = feature_scale(train_turns, config.standardize)
    expert_counts = mean_feature_counts(expert) / scale
    if initial_weights is not None:
        w0, start = np.asarray(initial_weights, dtype=np.float64), "given"
    elif config.start == "per-turn":  # eq. 7.5 as the expert's log-likelihood, on the expert's own turns
        per_turn_config = IrlConfig(policy="softmax", seed=config.seed, threads=config.threads)
        per_turn = fit_maxent_irl(expert, validation, per_turn_config)
        w0 = per_turn.weights.values
        start = (f"per-turn MaxEnt fit (softmax, l2 {per_turn_config.l2:g}, kept iteration "
                 f"{per_turn.best_iteration})")
    else:
        w0, start = np.zeros(len(names)), "zero"
    if w0.shape != (len(names),) or not np.all(np.isfinite(w0)):
        raise ValueError(f"initial_weights must be {len(names)} finite numbers, got shape {w0.shape}")
    adam, x = AdamAscent(config.learning_rate), w0 * scale
    held_out = validation_turns if validation_turns is not None else train_turns

    def record(iteration: int, gap: float, w: np.ndarray) -> tuple[IterationRecord, tuple | None]:
        """The iteration's scores and its selection key (None: not evaluated this iteration)."""
        train_agreement = train_turns.agreement(w)
        validation_agreement = validation_turns.agreement(w) if validation_turns is not None else None
        agreement_key = held_out.agreement(w)
        if config.select != "accuracy" or evaluate is None:  # (accuracy without evaluate is refused above)
            likelihood = log_likelihood(held_out, w)
            key = (likelihood, agreement_key) if config.select == "log_likelihood" else (agreement_key, likelihood)
            return IterationRecord(iteration, gap, train_agreement, validation_agreement), key
        due = iteration % config.evaluate_every == 0 or iteration == config.max_iterations
        if not due:
            return IterationRecord(iteration, gap, train_agreement, validation_agreement), None
        score = checked_score(evaluate(w), iteration)
        return IterationRecord(iteration, gap, train_agreement, validation_agreement, score), (score, agreement_key)

    best_w = w0.copy()
    first, best_key = record(0, float("nan"), best_w)
    history, best_iteration = [first], 0
    if progress is not None:
        progress(first, time.perf_counter() - started)
    for iteration in range(1, config.max_iterations + 1):
        episodes = [_checked(episode, names)
                    for episode in rollouts(x / scale, iteration, config.rollouts_per_iteration)]
        if len(episodes) != config.rollouts_per_iteration:
            raise ValueError(f"iteration {iteration}: the rollouts returned {len(episodes)} episodes, "
                             f"{config.rollouts_per_iteration} were asked for")
        learner = (mean_expected_feature_counts(episodes, x / scale) if config.expected_counts
                   else mean_feature_counts(episodes))
        gap = expert_counts - learner / scale  # eq. 7.7 in standardised units
        ascent = (gap - config.l2 * x) * identifiable
        x = adam.step(x, ascent) if config.optimizer == "adam" else x + config.learning_rate * ascent
        w = x / scale
        entry, key = record(iteration, float(np.linalg.norm(gap)), w)
        history.append(entry)
        if key is not None and (best_key is None or key > best_key):
            best_key, best_w, best_iteration = key, w, iteration
        if progress is not None:
            progress(entry, time.perf_counter() - started)
    if evaluate is not None and config.select != "accuracy":  # the kept iterate's task accuracy, for the record
        kept = history[best_iteration]
        history[best_iteration] = replace(kept, evaluation=checked_score(evaluate(best_w), best_iteration))
    settings = {"method": "maxent-irl-feature-matching", "optimizer": config.optimizer, "l2": float(config.l2),
                "learning_rate": float(config.learning_rate),
                "rollouts_per_iteration": config.rollouts_per_iteration,
                "learner_counts": "expected under the policy" if config.expected_counts else "sampled",
                "start": start,
                "select_by": "evaluation" if config.select == "accuracy" else config.select}
    if evaluate is not None and config.select == "accuracy":
        settings["evaluate_every"] = config.evaluate_every
    return make_result(names, best_w, identifiable, history, best_iteration, config.max_iterations, False, settings,
                       train_turns, validation_turns, started)


def checked_score(score, iteration: int) -> float:
    """An evaluation's score as a float; a non-finite one is a bug in the caller's ``evaluate``."""
    score = float(score)
    if not np.isfinite(score):
        raise ValueError(f"the evaluation of iteration {iteration} returned {score}; it must be a finite number")
    return score


def _checked(episode, names: tuple[str, ...]) -> QuestioningEpisode:
    if not isinstance(episode, QuestioningEpisode):
        raise ValueError(f"the rollout function must return a QuestioningEpisode, got {type(episode).__name__}")
    if episode.feature_names != names:
        raise ValueError(f"a rollout episode has features {list(episode.feature_names)}, the expert's are "
                         f"{list(names)}; they must match")
    return episode
