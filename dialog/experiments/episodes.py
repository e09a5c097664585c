"""One regression episode: a strategy, a condition, a training data set and a seed.

Runs the real dialog manager with a scripted teacher on observation pools and
returns the per-turn series the reports and baselines need.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from dialog.embodied import load_embodied_costs
from dialog.episode import build_episode, embodied_timing, make_teacher
from dialog.experiments.pools import PoolEnvironment, load_pools
from dialog.experiments.suite import Condition
from dialog.manager import episode_generators
from dialog.settings import EpisodeSettings
from dialog.threads import one_blas_thread
from dialog.transcripts.jsonl import TranscriptWriter
from dialog.user_weights import UserWeights
from learning.errors import SettingsError
from learning.strategies import Strategy

SERIES = ("turn", "accuracy", "questions", "label", "demo", "feature", "spent")


@dataclass(frozen=True)
class EpisodeSpec:
    suite: str
    task: str
    kitchen: str
    strategy: str
    condition: Condition
    dataset: int
    seed: int
    costs: tuple  # ((kind, cost), ...), hashable
    teacher: tuple  # ((option, value), ...)
    transcript: str
    plan: tuple = ()  # ((data-set plan option, value), ...), see dialog.experiments.pools.PLAN_OPTIONS
    data_seed: int = 0  # the seed the pools were rendered from
    weights: UserWeights | None = None  # a user's DT weights (regress --weights NAME=FILE); None: built-in strategy

    @property
    def episode_seed(self) -> int:
        """Scenes and teacher depend on the seed and data set, never on the strategy."""
        return self.seed * 1000 + self.dataset

    @property
    def label(self) -> str:
        return f"{self.strategy}/{self.condition.name}/d{self.dataset}/s{self.seed}"

    def settings(self) -> EpisodeSettings:
        """The episode's settings: this spec's task, kitchen, strategy and costs, the condition's allocation."""
        condition = self.condition
        return EpisodeSettings(task=self.task, kitchen=self.kitchen, strategy=self.strategy, seed=self.episode_seed,
                               turns=condition.turns, budget=condition.budget, change_every=condition.change_every,
                               costs=dict(self.costs), seconds=condition.seconds,
                               until_budget_spent=condition.until_budget_spent,
                               weights=None if self.weights is None else self.weights.record())


TEACHER_OPTIONS = ("kind", "mislabel_rate", "dont_know_rate", "feature_quality", "feature_recall", "feature_noise",
                   "feature_dont_know_rate")


def suite_teacher(options: dict, rng: np.random.Generator, clock=None, answer_delays: dict | None = None):
    """A scripted teacher (``kind = "scripted"``, the default; ``"oracle"`` = perfect) from suite options; with
    embodied costs it answers after ``answer_delays`` (per query kind) on the episode's ``clock``."""
    unknown = sorted(set(options) - set(TEACHER_OPTIONS))
    kind = options.get("kind", "scripted")
    if unknown or kind not in ("scripted", "oracle"):
        raise SettingsError(f"teacher options {', '.join(unknown) or kind} not supported; accepted: kind = "
                            f"'scripted' or 'oracle', {', '.join(TEACHER_OPTIONS[1:])} (each 0..1)")
    return make_teacher(kind, rng=rng, clock=clock, answer_delays=answer_delays,
                        **{k: v for k, v in options.items() if k != "kind"})


def run_episode(spec: EpisodeSpec, strategy: Strategy | None = None) -> dict:
    """Run one episode; returns its spec, per-turn series, final accuracy, the per-turn utility terms of the
    strategy's decisions (``decision_terms``, see ``TurnRecords``), wall time and CPU time.

    ``strategy`` (default: the one ``spec`` names) is an already built strategy, e.g. IRL's MaxEnt policy,
    which the caller can read after the episode (dialog.experiments.irl_rollouts)."""
    with one_blas_thread():
        return _run_episode(spec, strategy)


def _run_episode(spec: EpisodeSpec, strategy: Strategy | None = None) -> dict:
    started, started_cpu = time.perf_counter(), time.process_time()
    pools = load_pools(spec.task, spec.kitchen, spec.dataset + 1, spec.plan, data_seed=spec.data_seed)
    condition = spec.condition
    scenes = -(-condition.turns // max(condition.change_every, 1))
    if condition.seconds is not None:  # embodied costs: the scenes come with time (dialog/embodied.py)
        scenes = max(1, int(-(-condition.seconds // load_embodied_costs().scene_seconds(condition.change_every))))
    environment = PoolEnvironment(pools.train[spec.dataset], pools.test, pools.task, scenes,
                                  condition.objects_per_scene, condition.state_schedule)
    settings = spec.settings()
    rngs = episode_generators(settings.seed)
    timing = embodied_timing(condition.seconds)
    teacher = suite_teacher(dict(spec.teacher), rngs["teacher"], timing.clock, timing.answer_delays)
    Path(spec.transcript).parent.mkdir(parents=True, exist_ok=True)
    turns = TurnRecords()
    with TranscriptWriter(spec.transcript) as transcript:
        result = build_episode(settings, environment, teacher, transcript, strategy=strategy, rngs=rngs,
                               say=lambda _: None, clock=timing.clock, observers=(turns,)).run()
    series = series_from_transcript(turns.records)
    return {"spec": asdict(spec), "label": spec.label, "series": series, "accuracy": result.accuracy,
            "decision_terms": turns.terms, "ended": result.ended, "seconds": time.perf_counter() - started,
            "cpu_seconds": time.process_time() - started_cpu}


class TurnRecords:
    """An observer keeping every turn record as the manager wrote it to the transcript, so that the series are
    built from the records in memory instead of reading the file back (JSON keeps every value exactly), and
    beside each the strategy's utility terms of that turn's decision (DT's ``Decision.terms``; {} for a strategy
    without them). The terms stay out of the transcript and the series: the reports read them from memory."""

    def __init__(self) -> None:
        self.records: list[dict] = []
        self.terms: list[dict[str, float]] = []
        self._pending: dict[str, float] = {}

    def on_decision(self, decision) -> None:
        self._pending = dict(decision.terms)

    def on_turn(self, record: dict, scene) -> None:
        self.records.append(record)
        self.terms.append(self._pending)
        self._pending = {}


def series_from_transcript(records: list[dict]) -> dict[str, list]:
    """Per-turn cumulative counts and accuracy from a transcript."""
    series = {name: [] for name in SERIES}
    counts = {"label": 0, "demo": 0, "feature": 0}
    spent = 0.0
    for record in records:
        kind = record["action"]["kind"]
        if kind in counts:
            counts[kind] += 1
        spent += record["cost"]
        series["turn"].append(record["turn"])
        series["accuracy"].append(record["accuracy"])
        series["questions"].append(sum(counts.values()))
        for name in counts:
            series[name].append(counts[name])
        series["spent"].append(spent)
        if "seconds" in record:  # embodied costs: seconds used by the end of the turn
            series.setdefault("seconds", []).append(record["ended"])
    return series
