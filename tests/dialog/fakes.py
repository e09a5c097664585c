"""A fake world for loop tests: Gaussian blobs per concept, no simulator; and a strategy that follows a script."""

import numpy as np

from bullet_world.scene import Scene, SceneTruth
from learning.actions import Decision, NoQuery

CONCEPTS = ("main dish", "snack", "fruit", "beverage")
CENTRES = np.array([[0, 0, 0], [3, 0, 0], [0, 3, 0], [0, 0, 3]], dtype=float)


class FakeEnvironment:
    concepts = CONCEPTS
    feature_names = ("f1", "f2", "f3")
    test_scenes = 3

    def __init__(self, objects=8, missing=()):
        self.objects = objects
        self.missing = tuple(missing)  # concepts never present in a scene (for demonstrations of absent ones)
        self.scene_count = 0
        self.pointed = []

    def _scene(self, rng, missing=()):
        present = [c for c in CONCEPTS if c not in missing]
        concepts = tuple(present[i % len(present)] for i in range(self.objects))
        X = np.vstack([CENTRES[CONCEPTS.index(c)] + rng.normal(0, 0.4, 3) for c in concepts])
        self.scene_count += 1
        truth = SceneTruth(concepts, concepts, tuple(range(self.objects)), X.copy(), np.ones((self.objects, 3)))
        return Scene(self.scene_count, X, self.feature_names, X.copy(), np.ones(self.objects),
                     np.ones((self.objects, 3)) / 2, truth)

    def next_scene(self, rng):
        return self._scene(rng, self.missing)

    def point_at(self, scene, index):
        self.pointed.append((scene.scene_id, index))
        return {"reached": True}

    def test_set(self, n_scenes, rng):
        scenes = [self._scene(rng) for _ in range(n_scenes)]
        return np.vstack([s.X for s in scenes]), np.concatenate([s.truth.concepts for s in scenes])


class PantryEnvironment(FakeEnvironment):
    """A fake world whose pantry always has an example; pointing takes simulated time."""

    def __init__(self, objects=8, missing=()):
        super().__init__(objects, missing)
        self.fetched = []

    def point_at(self, scene, index):
        super().point_at(scene, index)
        return {"reached": True, "sim_seconds": 1.5}

    def can_fetch(self, concept):
        return True

    def fetch(self, scene, concept, rng):
        x = CENTRES[CONCEPTS.index(concept)] + rng.normal(0, 0.4, 3)
        self.fetched.append(concept)
        return {"x": x, "kind": f"{concept}-from-pantry", "position": [0.0, 0.0], "sim_seconds": 2.0}


class ScriptedStrategy:
    """Takes the actions of a list in turn (then stays quiet); draws from its stream like a real strategy."""

    name = "scripted"

    def __init__(self, actions):
        self.actions = list(actions)
        self.calls = 0

    def choose(self, state, rng):
        rng.random()
        action = self.actions[self.calls] if self.calls < len(self.actions) else NoQuery()
        self.calls += 1
        return Decision(action, f"step {self.calls} of my script")


class QuittingTeacher:
    """A scripted teacher that says "quit" at turn ``quit_at`` (None: never), to test ending and resuming."""

    def __init__(self, inner, quit_at=None):
        self.inner, self.quit_at = inner, quit_at

    def show(self, prompt):
        pass

    def listen(self, prompt, deadline):
        return "quit" if prompt.turn == self.quit_at else self.inner.listen(prompt, deadline)

    def tell(self, text):
        pass

    def fast_forward(self, prompt):
        self.inner.fast_forward(prompt)
