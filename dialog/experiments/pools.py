"""Episodes on recorded observation pools: scenes drawn from a data set, no rendering (thesis §6.5.3).

As in the thesis, every new scene samples one observation per scene object
from a training pool, stratified over the concepts; accuracy is measured on a
held-out test pool. The pools are the simulator's cached data sets
(:func:`bullet_world.datasets.load_datasets`, with the Panda attached so its
features are in every row).

Groundings that change over time (prepare-lunch, thesis §6.6.2) follow one of two schedules
(docs/open-settings.md): ``per-scene``, the thesis's §6.5.3 sampling, draws every object of a new scene from
all rows of its concept, every state as the data set holds it; ``episode-clock`` draws a kind with states in
order (pasta boxed -> in a pot -> in a bowl) in the state that matches how far the episode has gone, so the
main dish the robot sees early looks unlike the one it sees late. The test pool keeps every state either way.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from bullet_world.catalogue import Task, load_task
from bullet_world.datasets import Pool, load_datasets
from bullet_world.scene import Scene, SceneTruth
from dialog.experiments.suite import STATE_SCHEDULES
from learning.errors import SettingsError
from learning.limits import check_limit

PLAN_OPTIONS = ("pool_size", "test_size", "objects_per_scene")


@dataclass(frozen=True)
class PoolSet:
    """The training pools, the test pool and the task they were rendered for."""

    train: tuple[Pool, ...]
    test: Pool
    task: Task


# progress(done, total, message): called after each pool is rendered (never when the pools come from the cache)
RenderProgress = Callable[[int, int, str], None]
KEPT_POOL_SETS = 4  # pool sets kept in memory per process
_loaded: dict[tuple, PoolSet] = {}  # by (task, kitchen, pools in the data set file, plan options, data seed)
_pools_in_plan: dict[str, int] = {}  # each task's own number of training pools (its [datasets] plan)


def load_pools(task: str, kitchen: str, datasets: int, plan_options: tuple = (),
               progress: RenderProgress | None = None, data_seed: int = 0) -> PoolSet:
    """``datasets`` training pools and the test pool, from the cache (rendered once, then reused).

    ``plan_options`` ((name, value), ...) overrides the task's data-set plan (``pool_size``,
    ``test_size``, ``objects_per_scene``); accepted names are listed in the error otherwise.
    ``progress`` hears of every pool rendered on a first run. ``data_seed`` is the seed the pools are
    rendered from (0: the data every report so far was made on); another seed gives fresh data sets.
    """
    if isinstance(data_seed, bool) or not isinstance(data_seed, int | np.integer) or data_seed < 0:
        raise SettingsError(f"data seed must be a whole number >= 0, got {data_seed!r}")
    if isinstance(datasets, bool) or not isinstance(datasets, int | np.integer) or datasets < 1:
        raise SettingsError(f"datasets must be a whole number of at least 1 (training data sets), got {datasets!r}")
    check_limit("datasets", datasets)
    if task not in _pools_in_plan:
        _pools_in_plan[task] = load_task(task).datasets.pools
    # Fewer pools than the plan's come from the plan's one file: one entry serves every count up to it, so a
    # sweep over data sets 0..4 loads the file once, not once per data set.
    in_file = max(int(datasets), _pools_in_plan[task])
    key = (task, kitchen, in_file, tuple(plan_options), int(data_seed))
    if key not in _loaded:
        while len(_loaded) >= KEPT_POOL_SETS:
            _loaded.pop(next(iter(_loaded)))
        _loaded[key] = _load_pools(*key, progress)
    pools = _loaded[key]
    return pools if len(pools.train) == datasets else replace(pools, train=pools.train[:datasets])


def _load_pools(task: str, kitchen: str, datasets: int, plan_options: tuple, data_seed: int, progress) -> PoolSet:
    from robot import Arm

    loaded = load_task(task)
    options = dict(plan_options)
    unknown = sorted(set(options) - set(PLAN_OPTIONS))
    if unknown:
        raise SettingsError(f"unknown data-set options {unknown}; accepted: {', '.join(PLAN_OPTIONS)}")
    plan = replace(loaded.datasets, **{name: int(value) for name, value in options.items()})
    plan = replace(plan, pools=max(datasets, plan.pools))  # fewer pools reuse the task's cached set
    total, rendered = plan.pools + 1, []

    def pool_rendered(message: str) -> None:
        if progress is not None and message.startswith(f"{task}/{kitchen}: pool "):
            rendered.append(message)
            progress(len(rendered), total, message)

    sets = load_datasets(task, kitchen, seed=data_seed, plan=plan, robot_factory=Arm, progress=pool_rendered)
    return PoolSet(sets.train[:datasets], sets.test, loaded)


def state_order(task: Task) -> dict[str, tuple[str, ...]]:
    """Each kind's states in the order they happen (kinds without states are left out)."""
    return {kind.name: kind.state_names for kind in task.kinds if len(kind.states) > 1}


class PoolEnvironment:
    """The manager's environment over a training pool and a test pool (no arm: nothing to point with)."""

    def __init__(self, train: Pool, test: Pool, task: Task, scenes_per_episode: int = 1,
                 objects_per_scene: int | None = None, state_schedule: str = "episode-clock"):
        concepts = task.concepts
        missing = sorted(set(concepts) - set(train.concepts.tolist()))
        if missing:
            raise SettingsError(f"training pool has no observations of {missing}")
        size = task.objects_per_scene if objects_per_scene is None else int(objects_per_scene)
        if not 1 <= size <= task.max_objects_per_scene:
            raise SettingsError(f"objects_per_scene {size} is not accepted for task '{task.name}': a scene holds "
                                f"1 to {task.max_objects_per_scene} objects")
        if state_schedule not in STATE_SCHEDULES:
            raise SettingsError(f"state schedule {state_schedule!r} is not accepted; choose one of "
                                f"{', '.join(STATE_SCHEDULES)}")
        self.state_schedule = state_schedule
        self.train, self.test = train, test
        self.concepts = tuple(concepts)
        self.feature_names = tuple(train.feature_names)
        self.objects_per_scene = size  # thesis §6.5: 55 in pack-lunchbox's experiments, 12 in prepare-lunch's
        self.relevant_features = task.relevant_features
        self.scenes_per_episode = max(int(scenes_per_episode), 1)
        self._by_concept = {c: np.flatnonzero(train.concepts == c) for c in self.concepts}
        self._stage_of_row = self._stages(train, state_order(task))
        self._scene_count = 0

    @staticmethod
    def _stages(pool: Pool, order: dict[str, tuple[str, ...]]) -> np.ndarray:
        """For every row, its state's place in its kind's order as a fraction in [0, 1) (-1: no states)."""
        stages = np.full(len(pool), -1.0)
        for row, (kind, state) in enumerate(zip(pool.kinds.tolist(), pool.states.tolist())):
            states = order.get(kind)
            if states and state in states:
                stages[row] = states.index(state) / len(states)
        return stages

    def _rows_now(self, concept: str, progress: float) -> np.ndarray:
        """Rows of ``concept`` whose state matches the episode's progress (all rows of stateless kinds); every row
        with the ``per-scene`` schedule."""
        rows = self._by_concept[concept]
        stages = self._stage_of_row[rows]
        if self.state_schedule == "per-scene" or (stages < 0).all():
            return rows
        # a row's state spans [stage, stage + 1/len(states)); pick the latest state begun by now
        begun = rows[(stages >= 0) & (stages <= progress)]
        if len(begun):
            latest = self._stage_of_row[begun].max()
            current = begun[self._stage_of_row[begun] == latest]
            return np.concatenate([current, rows[stages < 0]])
        return rows

    def next_scene(self, rng: np.random.Generator) -> Scene:
        """One observation per scene object, concepts as evenly represented as the count allows."""
        progress = min(self._scene_count / self.scenes_per_episode, 1.0)
        sequence = [self.concepts[i % len(self.concepts)] for i in range(self.objects_per_scene)]
        rng.shuffle(sequence)
        rows = []
        for concept in sequence:
            candidates = self._rows_now(concept, progress)
            rows.append(candidates[rng.integers(len(candidates))])
        rows = np.array(rows)
        self._scene_count += 1
        n = len(rows)
        truth = SceneTruth(tuple(self.train.concepts[rows].tolist()), tuple(self.train.kinds[rows].tolist()),
                           tuple(rows.tolist()), np.zeros((n, 3)), np.zeros((n, 3)),
                           states=tuple(self.train.states[rows].tolist()))
        return Scene(self._scene_count, self.train.X[rows], self.feature_names, np.zeros((n, 3)), np.zeros(n),
                     np.zeros((n, 3)), truth)

    def point_at(self, scene: Scene, object_index: int) -> dict:
        return {"simulated": False}

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        return self.test.X, self.test.concepts
