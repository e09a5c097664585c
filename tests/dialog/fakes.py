"""A fake world for loop tests: Gaussian blobs per concept, no simulator."""

import numpy as np

from bullet_world.scene import Scene, SceneTruth

CONCEPTS = ("main dish", "snack", "fruit", "beverage")


class FakeEnvironment:
    concepts = CONCEPTS
    feature_names = ("f1", "f2", "f3")
    test_scenes = 3

    def __init__(self, objects=8):
        self.objects = objects
        self.scene_count = 0
        self.pointed = []

    def _scene(self, rng):
        concepts = tuple(CONCEPTS[i % 4] for i in range(self.objects))
        centres = np.array([[0, 0, 0], [3, 0, 0], [0, 3, 0], [0, 0, 3]], dtype=float)
        X = np.vstack([centres[CONCEPTS.index(c)] + rng.normal(0, 0.4, 3) for c in concepts])
        self.scene_count += 1
        truth = SceneTruth(concepts, concepts, tuple(range(self.objects)), X.copy(), np.ones((self.objects, 3)))
        return Scene(self.scene_count, X, self.feature_names, X.copy(), np.ones(self.objects),
                     np.ones((self.objects, 3)) / 2, truth)

    def next_scene(self, rng):
        return self._scene(rng)

    def point_at(self, scene, index):
        self.pointed.append((scene.scene_id, index))
        return {"reached": True}

    def test_set(self, n_scenes, rng):
        scenes = [self._scene(rng) for _ in range(n_scenes)]
        return np.vstack([s.X for s in scenes]), np.concatenate([s.truth.concepts for s in scenes])
