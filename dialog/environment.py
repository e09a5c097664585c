"""The manager's view of the world: scenes, a held-out test set, and a pointing gesture.

``SimulatedKitchen`` is the real one (PyBullet world + Panda arm); tests may pass
any object with the same methods.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from bullet_world import Scene, World
from robot import Arm
from robot.gestures import point_at


class Environment(Protocol):
    concepts: tuple[str, ...]
    feature_names: tuple[str, ...]

    def next_scene(self, rng: np.random.Generator) -> Scene: ...

    def point_at(self, scene: Scene, object_index: int) -> dict: ...

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]: ...


class SimulatedKitchen:
    """A PyBullet kitchen with the Panda: real rendering, perception and pointing."""

    def __init__(self, task: str = "pack-lunchbox", kitchen: str = "kitchen-1", seed: int = 0):
        self.world = World(task=task, kitchen=kitchen, seed=seed)
        self.arm = Arm(self.world)
        self.concepts = self.world.task.concepts
        self.feature_names = self.world.feature_names
        self.test_scenes = self.world.task.test_scenes

    def next_scene(self, rng: np.random.Generator) -> Scene:
        return self.world.new_scene(rng)

    def point_at(self, scene: Scene, object_index: int) -> dict:
        """Really move the arm; report where the fingertip ended relative to the object."""
        result = point_at(self.arm, scene.positions[object_index], scene.tops[object_index])
        offset = self.arm.fingertip_position() - scene.truth.positions[object_index]
        return {"reached": result.reached, "horizontal_error_m": round(float(np.hypot(*offset[:2])), 4),
                "sim_seconds": round(result.sim_seconds, 3)}

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Stack ``n_scenes`` freshly sampled scenes as held-out instances."""
        scenes = [self.world.new_scene(rng) for _ in range(n_scenes)]
        return np.vstack([s.X for s in scenes]), np.concatenate([s.truth.concepts for s in scenes])

    def close(self) -> None:
        self.world.close()
