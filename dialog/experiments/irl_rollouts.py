"""IRL's rollouts of the real dialog loop in the training condition (thesis §7.3.2, §7.4.1, eq. 7.7).

A rollout is one regression episode (``dialog.experiments.episodes.run_episode``:
the dialog manager, a scripted teacher, the cached data sets of the training
condition) whose strategy is the MaxEnt policy with the current weights
(``learning.strategies.maxent_policy``, actions sampled with a generator seeded
by (fit seed, iteration, rollout)). The recorded turns are the learner's
trajectory for the feature counts of eq. 7.7. A validation episode is the same
loop with the greedy DT rule and those weights; the iterate whose validation
episodes end with the best mean held-out accuracy is kept.

Seeds: training rollouts use episode seeds from ``TRAIN_SEED_BASE`` up (one
per iteration and rollout), validation episodes ``VALIDATION_SEED_BASE`` up,
so the two never meet, and neither meets the ch7 suite's seeds 0-4.
Rollouts run on local worker processes (default: one per core) or on Ray.
"""

from __future__ import annotations

import os
import tempfile
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from dialog.experiments.episodes import EpisodeSpec, run_episode
from dialog.experiments.suite import SUITE_DIR, Condition, load_suite
from learning.errors import SettingsError
from learning.irl.demonstrations import QuestioningEpisode
from learning.irl.rollouts import Evaluate, RolloutBatch, rollout_generator
from learning.strategies.decision_theoretic import DecisionTheoreticStrategy
from learning.strategies.maxent_policy import MaxEntPolicyStrategy

TRAINING_SUITE = SUITE_DIR / "ch7-training.toml"
TRAIN_SEED_BASE = 1000
VALIDATION_SEED_BASE = 500
MAX_VALIDATION_EPISODES = TRAIN_SEED_BASE - VALIDATION_SEED_BASE


@dataclass(frozen=True)
class TrainingCondition:
    """Where the learner's rollouts are played: the thesis's training condition (§7.4.1)."""

    task: str = "prepare-lunch"
    kitchen: str = "kitchen-1"
    condition: Condition = Condition("training", 15.0, 30, 10)
    costs: tuple = (("demo", 2.0), ("feature", 2.0), ("label", 1.0), ("none", 0.0))
    teacher: tuple = ()
    data_seed: int = 100
    datasets: int = 5  # training pools; rollout seed k plays on pool k mod datasets
    plan: tuple = ()
    source: str = "built-in defaults (the thesis's training condition)"

    def spec(self, seed: int) -> EpisodeSpec:
        """The episode spec of episode seed ``seed`` (its transcript goes to a scratch directory)."""
        return EpisodeSpec(suite="irl-rollouts", task=self.task, kitchen=self.kitchen, strategy="irl-learner",
                           condition=self.condition, dataset=seed % self.datasets, seed=seed, costs=self.costs,
                           teacher=self.teacher, transcript="", plan=self.plan, data_seed=self.data_seed)

    def provenance(self) -> dict:
        c = self.condition
        return {"condition_source": self.source, "task": self.task, "kitchen": self.kitchen, "budget": c.budget,
                "turns": c.turns, "change_every": c.change_every, "data_seed": self.data_seed,
                "costs": ", ".join(f"{kind} {cost:g}" for kind, cost in self.costs)}


def training_condition(path: str | Path = TRAINING_SUITE) -> TrainingCondition:
    """The training condition from the ``ch7-training`` suite (its first condition), or the thesis's values."""
    path = Path(path)
    if not path.exists():
        return TrainingCondition()
    suite = load_suite(path)
    return TrainingCondition(task=suite.task, kitchen=suite.kitchen, condition=suite.conditions[0],
                             costs=tuple(sorted((k, float(v)) for k, v in suite.costs.items())),
                             teacher=tuple(sorted(suite.teacher.items())), data_seed=suite.data_seed,
                             datasets=suite.datasets, plan=suite.plan_options, source=f"dialog/suites/{path.name}")


@dataclass(frozen=True)
class RolloutTask:
    """One episode to play: ``policy_seed`` (seed, iteration, index) samples from the MaxEnt policy; None: greedy DT."""

    spec: EpisodeSpec
    weights: tuple[float, ...]
    policy_seed: tuple[int, int, int] | None = None


def play(task: RolloutTask) -> tuple[QuestioningEpisode | None, float]:
    """Play one rollout: (the learner's recorded episode, or None for a greedy one; its final accuracy)."""
    weights = np.array(task.weights)
    if task.policy_seed is None:
        strategy = DecisionTheoreticStrategy(weights, name="irl-iterate")
    else:
        strategy = MaxEntPolicyStrategy(weights, rollout_generator(*task.policy_seed))
    with tempfile.TemporaryDirectory(prefix="teachbot-irl-") as scratch:
        spec = replace(task.spec, transcript=str(Path(scratch) / "rollout.jsonl"))
        result = run_episode(spec, strategy)
    if task.policy_seed is None:
        return None, float(result["accuracy"])
    metadata = {"source": "rollout", "seed": task.spec.seed, "dataset": task.spec.dataset,
                "accuracy": round(float(result["accuracy"]), 6)}
    return strategy.episode(f"rollout-s{task.spec.seed}", metadata), float(result["accuracy"])


class RolloutPool:
    """Plays rollout tasks on local worker processes (default: one per core) or Ray; results in task order."""

    def __init__(self, workers: int | None = None, ray_address: str | None = None):
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise SettingsError(f"workers must be a whole number >= 1, got {workers!r}")
        self.workers = workers or os.cpu_count() or 1
        self.ray_address = ray_address
        self._executor: ProcessPoolExecutor | None = None
        self._ray = self._remote = None

    @property
    def where(self) -> str:
        return f"ray {self.ray_address}" if self.ray_address else f"{self.workers} local worker(s)"

    def __enter__(self) -> RolloutPool:
        if self.ray_address:
            from dialog.experiments.runner import connect_ray

            self._ray = connect_ray(self.ray_address, "learn-weights")
            self._remote = self._ray.remote(play)
        return self

    def __exit__(self, *exc) -> None:
        if self._executor is not None:
            self._executor.shutdown(cancel_futures=True)
            self._executor = None

    def map(self, tasks: list[RolloutTask]) -> list[tuple[QuestioningEpisode | None, float]]:
        if self._remote is not None:
            return self._ray.get([self._remote.remote(task) for task in tasks])
        if self.workers == 1 or len(tasks) == 1:
            return [play(task) for task in tasks]
        if self._executor is None:  # started on first use; spawn: forked children should not inherit torch's threads
            self._executor = ProcessPoolExecutor(self.workers, mp_context=get_context("spawn"))
        return list(self._executor.map(play, tasks))


def training_seed(iteration: int, index: int, count: int) -> int:
    """The episode seed of rollout ``index`` of ``iteration`` (1-based) with ``count`` rollouts an iteration."""
    return TRAIN_SEED_BASE + (iteration - 1) * count + index


def validation_seeds(count: int) -> tuple[int, ...]:
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_VALIDATION_EPISODES:
        raise SettingsError(f"validation episodes must be a whole number in 1..{MAX_VALIDATION_EPISODES}, "
                            f"got {count!r}")
    return tuple(range(VALIDATION_SEED_BASE, VALIDATION_SEED_BASE + count))


def rollout_functions(condition: TrainingCondition, pool: RolloutPool, seed: int,
                      n_validation: int) -> tuple[RolloutBatch, Evaluate]:
    """``rollouts(w, iteration, count)`` for eq. 7.7 and ``evaluate(w)``: mean final accuracy on validation seeds."""
    held_out = validation_seeds(n_validation)

    def rollouts(weights: np.ndarray, iteration: int, count: int) -> list[QuestioningEpisode]:
        values = tuple(float(v) for v in weights)
        tasks = [RolloutTask(condition.spec(training_seed(iteration, index, count)), values, (seed, iteration, index))
                 for index in range(count)]
        return [episode for episode, _ in pool.map(tasks)]

    def evaluate(weights: np.ndarray) -> float:
        values = tuple(float(v) for v in weights)
        return float(np.mean([accuracy for _, accuracy in pool.map(
            [RolloutTask(condition.spec(s), values) for s in held_out])]))

    return rollouts, evaluate
