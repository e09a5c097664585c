"""Task data sets (thesis §6.5.1): disjoint training pools and a held-out test pool, made by the
simulator from seeds and cached on disk so that regression runs need not render again.

Each pool is a stratified sample of observed objects (rows of the feature
matrix, with concept, kind, state and scene of every row) taken from scenes
rendered with their own seed stream, so pools never share an observation.
The cache holds one NPZ (arrays) and one JSON (metadata) per data set, named
by a hash of everything that generates it: the data files, the generator code,
the plan, the seed, and whether a robot was attached. Change any of them and
the data set is built again.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from bullet_world.catalogue import DatasetPlan, load_task
from bullet_world.datafiles import DATA_DIR, cache_dir, one_builder, resolve, write_atomically
from bullet_world.world import World
from learning.errors import SettingsError

DATASET_VERSION = 1
GENERATOR_MODULES = ("bodies", "camera", "catalogue", "datafiles", "datasets", "features", "kitchen", "meshes",
                     "perception", "placement", "room", "scene", "sensors", "textures", "world")


@dataclass(frozen=True)
class Pool:
    """Observed objects: one feature row each, with its hidden truth."""

    X: np.ndarray
    concepts: np.ndarray
    kinds: np.ndarray
    states: np.ndarray
    scenes: np.ndarray
    feature_names: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.X)

    def take(self, rows) -> Pool:
        rows = np.asarray(rows)
        return Pool(self.X[rows], self.concepts[rows], self.kinds[rows], self.states[rows], self.scenes[rows],
                    self.feature_names)


@dataclass(frozen=True)
class TaskDatasets:
    """``train``: the disjoint training pools; ``test``: the held-out pool; ``metadata``: how they were made."""

    train: tuple[Pool, ...]
    test: Pool
    metadata: dict

    @property
    def feature_names(self) -> tuple[str, ...]:
        return self.test.feature_names


def generator_hash(task: str, kitchen: str, plan: DatasetPlan, seed: int, with_robot: bool) -> str:
    """Hash of the data files that make the data set (features, task, its objects, the kitchen), the
    generator's code, and the request."""
    digest = hashlib.sha256(f"{DATASET_VERSION}|{task}|{kitchen}|{plan}|{seed}|{with_robot}".encode())
    loaded = load_task(task)
    files = (DATA_DIR / "features.toml", Path(loaded.path), Path(loaded.objects_path), resolve("kitchens", kitchen))
    for path in files:
        digest.update(path.name.encode() + path.read_bytes())
    package = Path(__file__).parent
    for module in GENERATOR_MODULES:
        digest.update((package / f"{module}.py").read_bytes())
    if with_robot:
        digest.update((package.parent / "robot" / "arm.py").read_bytes())
    return digest.hexdigest()[:16]


def _stratified(pool: Pool, size: int, concepts, rng: np.random.Generator) -> Pool:
    """``size`` rows with the concepts as evenly represented as the size allows."""
    quota = [size // len(concepts) + (1 if i < size % len(concepts) else 0) for i in range(len(concepts))]
    rows = []
    for concept, count in zip(concepts, quota):
        available = np.flatnonzero(pool.concepts == concept)
        if len(available) < count:
            raise SettingsError(f"only {len(available)} observations of '{concept}' for a pool that needs {count}")
        rows.append(rng.choice(available, count, replace=False))
    return pool.take(np.sort(np.concatenate(rows)))


def _render_pool(world: World, size: int, stream: int, seed: int, concepts) -> Pool:
    per_scene = world.task.objects_per_scene
    scenes = math.ceil(size * 1.1 / per_scene) + 1  # a little spare so every concept fills its quota
    rng = np.random.default_rng([seed, stream])
    world.start_lesson()  # every pool is its own lesson: the room's noise summary starts afresh
    observed = [world.new_scene(rng) for _ in range(scenes)]
    pool = Pool(
        X=np.vstack([s.X for s in observed]),
        concepts=np.concatenate([np.array(s.truth.concepts, dtype=str) for s in observed]),
        kinds=np.concatenate([np.array(s.truth.kinds, dtype=str) for s in observed]),
        states=np.concatenate([np.array(s.truth.states, dtype=str) for s in observed]),
        scenes=np.concatenate([np.full(s.n_objects, index) for index, s in enumerate(observed)]),
        feature_names=observed[0].feature_names,
    )
    return _stratified(pool, size, concepts, np.random.default_rng([seed, stream, 1]))


def build_datasets(task: str, kitchen: str = "kitchen-1", seed: int = 0, plan: DatasetPlan | None = None,
                   robot_factory=None, progress=None) -> TaskDatasets:
    """Render the pools: ``plan.pools`` training pools and a test pool, each from its own seed stream.
    ``robot_factory(world)`` attaches a robot (e.g. ``robot.Arm``) so its features join the rows."""
    plan = plan or load_task(task).datasets
    started = time.perf_counter()
    with World(task=task, kitchen=kitchen, seed=seed, objects_per_scene=plan.objects_per_scene) as world:
        if robot_factory is not None:
            robot_factory(world)
        concepts = world.task.concepts
        pools = []
        for stream in range(plan.pools + 1):
            size = plan.test_size if stream == plan.pools else plan.pool_size
            pools.append(_render_pool(world, size, stream, seed, concepts))
            if progress:
                progress(f"{task}/{kitchen}: pool {stream + 1} of {plan.pools + 1} ({size} objects)")
    metadata = {"task": task, "kitchen": kitchen, "seed": seed, "plan": plan.__dict__, "concepts": list(concepts),
                "feature_names": list(pools[0].feature_names), "robot": robot_factory is not None,
                "build_seconds": round(time.perf_counter() - started, 1)}
    return TaskDatasets(tuple(pools[:-1]), pools[-1], metadata)


def _save(datasets: TaskDatasets, npz_path: Path, json_path: Path) -> None:
    arrays = {}
    for name, pool in [*((f"train{i}", p) for i, p in enumerate(datasets.train)), ("test", datasets.test)]:
        for field in ("X", "concepts", "kinds", "states", "scenes"):
            arrays[f"{name}_{field}"] = getattr(pool, field)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    write_atomically(npz_path, buffer.getvalue())
    write_atomically(json_path, (json.dumps(datasets.metadata, indent=1) + "\n").encode())


def _load(npz_path: Path, json_path: Path) -> TaskDatasets:
    metadata = json.loads(json_path.read_text())
    names = tuple(metadata["feature_names"])
    with np.load(npz_path, allow_pickle=False) as arrays:
        def pool(name: str) -> Pool:
            return Pool(*(arrays[f"{name}_{field}"] for field in ("X", "concepts", "kinds", "states", "scenes")),
                        feature_names=names)

        train = tuple(pool(f"train{i}") for i in range(metadata["plan"]["pools"]))
        test = pool("test")
    return TaskDatasets(train, test, metadata)


def load_datasets(task: str, kitchen: str = "kitchen-1", seed: int = 0, plan: DatasetPlan | None = None,
                  robot_factory=None, cache=None, rebuild: bool = False, progress=None) -> TaskDatasets:
    """The task's data sets from the cache, built (and cached) first when missing or out of date."""
    plan = plan or load_task(task).datasets
    key = generator_hash(task, kitchen, plan, seed, robot_factory is not None)
    folder = cache_dir(cache) / "datasets"
    stem = f"{_file_label(task)}-{_file_label(kitchen)}-seed{seed}-{key}"
    npz_path, json_path = folder / f"{stem}.npz", folder / f"{stem}.json"
    cached = None if rebuild else _cached(npz_path, json_path, progress)
    if cached is not None:
        return cached
    with one_builder(folder.parent / "locks" / f"{stem}.lock"):  # another process may be building it: wait, then read
        cached = None if rebuild else _cached(npz_path, json_path)
        if cached is not None:
            return cached
        datasets = build_datasets(task, kitchen, seed, plan, robot_factory, progress)
        datasets = replace(datasets, metadata=datasets.metadata | {"generator": key, "file": str(npz_path)})
        _save(datasets, npz_path, json_path)
    return datasets


def _file_label(name_or_path: str) -> str:
    """A task's or kitchen's name as part of a cache file's name: a .toml path by its file's stem (the key
    hashes the file's bytes), so a path never makes folders in the cache."""
    return Path(name_or_path).stem if str(name_or_path).endswith(".toml") else str(name_or_path)


def _cached(npz_path: Path, json_path: Path, progress=None) -> TaskDatasets | None:
    """The cached data sets, or None when they are missing or unreadable (then they are built again)."""
    if not (npz_path.exists() and json_path.exists()):
        return None
    try:
        return _load(npz_path, json_path)
    except (OSError, ValueError, KeyError) as error:
        if progress:
            progress(f"cached data set {npz_path.name} is unreadable ({error}); building it again")
        return None
