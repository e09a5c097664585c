"""One regression episode: a strategy, a condition, a training data set and a seed.

Runs the real dialog manager with a scripted teacher on observation pools and
returns the per-turn series the reports and baselines need.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.regress.pools import ObservationPool, PoolEnvironment
from dialog.regress.suite import Condition
from dialog.transcript import TranscriptWriter, read_transcript
from learning.strategies import make_strategy

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
    pool_scenes: int

    @property
    def episode_seed(self) -> int:
        """Scenes and teacher depend on the seed and data set, never on the strategy."""
        return self.seed * 1000 + self.dataset

    @property
    def label(self) -> str:
        return f"{self.strategy}/{self.condition.name}/d{self.dataset}/s{self.seed}"


@lru_cache(maxsize=4)
def load_pools(task: str, kitchen: str, datasets: int, pool_scenes: int) -> tuple:
    """``datasets`` disjoint training pools and one test pool, each of ``pool_scenes`` rendered scenes."""
    from bullet_world import World
    from robot import Arm

    with World(task=task, kitchen=kitchen, seed=0) as world:
        Arm(world)
        pools = []
        for index in range(datasets + 1):
            rng = np.random.default_rng([7, index])  # pool index -> disjoint streams of scenes
            scenes = [world.new_scene(rng) for _ in range(pool_scenes)]
            pools.append(ObservationPool(
                X=np.vstack([s.X for s in scenes]),
                concepts=np.array([c for s in scenes for c in s.truth.concepts], dtype=object),
                kinds=np.array([k for s in scenes for k in s.truth.kinds], dtype=object),
                feature_names=scenes[0].feature_names,
            ))
        return tuple(pools[:-1]), pools[-1], world.task.concepts, world.task.objects_per_scene


def make_teacher(options: dict, rng: np.random.Generator):
    from dialog.teachers import OracleTeacher

    unknown = sorted(set(options) - {"kind"})
    if options.get("kind", "oracle") != "oracle" or unknown:
        raise ValueError(f"teacher options {options} not supported; accepted: kind = 'oracle'")
    return OracleTeacher(rng)


def run_episode(spec: EpisodeSpec) -> dict:
    """Run one episode; returns its spec, per-turn series, final accuracy and wall time."""
    started = time.perf_counter()
    train, test, concepts, objects = load_pools(spec.task, spec.kitchen, spec.dataset + 1, spec.pool_scenes)
    environment = PoolEnvironment(train[spec.dataset], test, concepts, objects)
    condition = spec.condition
    config = EpisodeConfig(turns=condition.turns, budget=condition.budget, change_every=condition.change_every,
                           seed=spec.episode_seed, costs=dict(spec.costs))
    rngs = episode_generators(spec.episode_seed)
    Path(spec.transcript).parent.mkdir(parents=True, exist_ok=True)
    with TranscriptWriter(spec.transcript) as transcript:
        result = DialogManager(environment, make_teacher(dict(spec.teacher), rngs["teacher"]),
                               make_strategy(spec.strategy), config, transcript, rngs, say=lambda _: None).run()
    series = series_from_transcript(read_transcript(spec.transcript))
    return {"spec": asdict(spec), "label": spec.label, "series": series, "accuracy": result.accuracy,
            "seconds": time.perf_counter() - started}


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
    return series
