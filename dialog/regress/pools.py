"""Episodes on recorded observation pools: scenes drawn from a data set, no rendering (thesis §6.5.3).

As in the thesis, every new scene samples one observation per scene object
from a training pool, stratified over the concepts; accuracy is measured on a
held-out test pool. Pools come from the simulator (see ``load_pools``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bullet_world.scene import Scene, SceneTruth


@dataclass(frozen=True)
class ObservationPool:
    """Rows of observed objects: features, true concept and kind of each."""

    X: np.ndarray
    concepts: np.ndarray
    kinds: np.ndarray
    feature_names: tuple[str, ...]

    def __post_init__(self):
        if not (len(self.X) == len(self.concepts) == len(self.kinds)):
            raise ValueError(f"pool arrays differ in length: X {len(self.X)}, concepts {len(self.concepts)}, "
                             f"kinds {len(self.kinds)}")


class PoolEnvironment:
    """The manager's environment over a training pool and a test pool (no arm: nothing to point with)."""

    def __init__(self, train: ObservationPool, test: ObservationPool, concepts, objects_per_scene: int):
        missing = sorted(set(concepts) - set(train.concepts.tolist()))
        if missing:
            raise ValueError(f"training pool has no observations of {missing}")
        self.train, self.test = train, test
        self.concepts = tuple(concepts)
        self.feature_names = train.feature_names
        self.objects_per_scene = objects_per_scene
        self.test_scenes = 0
        self._by_concept = {c: np.nonzero(train.concepts == c)[0] for c in self.concepts}
        self._scene_count = 0

    def next_scene(self, rng: np.random.Generator) -> Scene:
        """One observation per scene object, concepts as evenly represented as the count allows."""
        sequence = [self.concepts[i % len(self.concepts)] for i in range(self.objects_per_scene)]
        rng.shuffle(sequence)
        rows = np.array([self._by_concept[c][rng.integers(len(self._by_concept[c]))] for c in sequence])
        self._scene_count += 1
        n = len(rows)
        X = self.train.X[rows]
        truth = SceneTruth(tuple(self.train.concepts[rows].tolist()), tuple(self.train.kinds[rows].tolist()),
                           tuple(rows.tolist()), np.zeros((n, 3)), np.zeros((n, 3)))
        return Scene(self._scene_count, X, self.feature_names, np.zeros((n, 3)), np.zeros(n), np.zeros((n, 3)),
                     truth)

    def point_at(self, scene: Scene, object_index: int) -> dict:
        return {"simulated": False}

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        return self.test.X, self.test.concepts
