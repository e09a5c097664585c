"""The manager's view of the world: scenes, a held-out test set, pointing, pictures, the pantry.

``SimulatedKitchen`` is the real one (PyBullet world + Panda arm); tests may pass
any object with ``concepts``, ``feature_names``, ``next_scene``, ``point_at``
and ``test_set``. The rest is optional and looked up with ``getattr``:
``locations`` (for descriptions), ``scene_picture`` (numbered pictures),
``can_fetch``/``fetch`` (pantry), ``relevant_features`` (for scripted teachers).
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np

from bullet_world import Scene, World
from dialog.pictures import annotate_scene, project_points, save_picture
from robot import Arm
from robot.gestures import point_at

PANTRY = "pantry"
DEFAULT_RADIUS_M = 0.06  # footprint radius assumed for an object whose drawn size has no usable dimensions
FETCH_CLEARANCE_M = 0.02  # free space kept around a fetched object's footprint
FETCH_TRIES = 60


def footprint_radius(draw: dict) -> float:
    """Radius of the circle around a drawn object's footprint (box: half diagonal; round: its radius)."""
    dims = draw.get("dimensions", {})
    if "length" in dims and "width" in dims:
        return 0.5 * float(np.hypot(dims["length"], dims["width"]))
    if "radius" in dims:
        return float(dims["radius"])
    return DEFAULT_RADIUS_M


class Environment(Protocol):
    concepts: tuple[str, ...]
    feature_names: tuple[str, ...]

    def next_scene(self, rng: np.random.Generator) -> Scene: ...

    def point_at(self, scene: Scene, object_index: int) -> dict: ...

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]: ...


class SimulatedKitchen:
    """A PyBullet kitchen with the Panda: real rendering, perception, pointing and fetching."""

    def __init__(self, task: str = "pack-lunchbox", kitchen: str = "kitchen-1", seed: int = 0,
                 pictures: bool = False):
        self.world = World(task=task, kitchen=kitchen, seed=seed)
        self.arm = Arm(self.world)
        self.concepts = self.world.task.concepts
        self.feature_names = self.world.feature_names
        self.test_scenes = self.world.task.test_scenes
        self.pictures = pictures
        self._scene_image = None  # (scene id, rgb, pixel position of every object)
        self._arm_out = False  # the arm pointed since the last scene: rest it before the world is observed again

    @property
    def locations(self) -> dict:
        return dict(self.world.kitchen.locations)

    @property
    def relevant_features(self) -> tuple[str, ...] | None:
        """The task's features that matter (ground truth, for scripted teachers only)."""
        names = getattr(self.world.task, "relevant_features", None)
        return tuple(names) if names else None

    def next_scene(self, rng: np.random.Generator) -> Scene:
        """The world changes: objects move on to their next state where the task has states (prepare
        lunch), else (or once every state is reached) a fresh sample of objects."""
        world = self.world
        if self._arm_out:  # a pointing arm left in the camera's view would hide objects of the next observation
            self.arm.rest()
            self._arm_out = False
        last_stage = max((len(getattr(k, "states", ())) for k in getattr(world, "kinds", ())), default=0) - 1
        if getattr(world.task, "has_states", False) and world.scene is not None and world.stage < last_stage:
            scene = world.advance_states(rng)
        elif getattr(world.task, "has_states", False):
            scene = world.new_scene(rng, stage=0)
        else:
            scene = world.new_scene(rng)
        self._scene_image = None
        if self.pictures:  # keep the frame now, while the arm rests out of the camera's view
            self._capture(scene)
        return scene

    def point_at(self, scene: Scene, object_index: int) -> dict:
        """Really move the arm; report where the fingertip ended relative to the object."""
        result = point_at(self.arm, scene.positions[object_index], scene.tops[object_index])
        self._arm_out = True
        tip = self.arm.fingertip_position()
        offset = tip - scene.truth.positions[object_index]
        return {"reached": result.reached, "horizontal_error_m": round(float(np.hypot(*offset[:2])), 4),
                "height_above_top_m": round(float(tip[2] - scene.tops[object_index]), 3),
                "sim_seconds": round(result.sim_seconds, 3)}

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Stack ``n_scenes`` freshly sampled scenes as held-out instances."""
        scenes = [self.world.new_scene(rng) for _ in range(n_scenes)]
        return np.vstack([s.X for s in scenes]), np.concatenate([s.truth.concepts for s in scenes])

    # -- pictures -----------------------------------------------------------------
    def _capture(self, scene: Scene) -> None:
        camera, images = self.world.camera, getattr(self.world, "images", None)
        if images is None or self.world.scene is not scene:  # the frame the scene was measured from, if kept
            images = camera.render(self.world.client, self.world.lighting)
        pixels = project_points(scene.positions, images.view_matrix, images.projection_matrix,
                                camera.width, camera.height)
        self._scene_image = (scene.scene_id, images.rgb, pixels)

    def scene_picture(self, scene: Scene, path: str | Path, highlight: int | None = None) -> Path:
        """Write the scene's camera image with every object's number (``highlight`` ringed) to ``path``."""
        if self._scene_image is None or self._scene_image[0] != scene.scene_id:
            self._capture(scene)
        _, rgb, pixels = self._scene_image
        return save_picture(path, annotate_scene(rgb, pixels, range(1, len(pixels) + 1), highlight))

    # -- the pantry -----------------------------------------------------------------
    def can_fetch(self, concept: str) -> bool:
        """Whether the task lets the robot fetch an example of ``concept`` from the kitchen's pantry."""
        allowed = getattr(self.world.task, "pantry_fetch", True)
        return bool(allowed) and PANTRY in self.world.kitchen.locations and concept in self.concepts

    def _free_spot(self, scene: Scene, radius: float, rng: np.random.Generator):
        region = self.world.kitchen.locations[PANTRY]
        occupied = np.asarray(scene.positions, dtype=float)[:, :2]
        if "size.length" in scene.feature_names:
            others = scene.feature("size.length") / 2
        else:
            others = np.full(len(occupied), 0.06)
        for _ in range(FETCH_TRIES):
            xy = np.array([rng.uniform(region.centre[i] - region.half_size[i], region.centre[i] + region.half_size[i])
                           for i in range(2)])
            if np.all(np.linalg.norm(occupied - xy, axis=1) >= others + radius + FETCH_CLEARANCE_M):
                return xy
        return None

    def fetch(self, scene: Scene, concept: str, rng: np.random.Generator) -> dict | None:
        """Reach into the pantry for an example of ``concept``, observe it, and put it back.

        The world spawns a new object of one of the concept's kinds at a free
        spot of the pantry region; its observed feature row is returned as
        ``x``. None when the pantry region has no free spot.
        """
        kinds = [k for k in getattr(self.world, "kinds", self.world.task.kinds) if k.concept == concept]
        if not kinds or not self.can_fetch(concept):
            return None
        kind = kinds[int(rng.integers(len(kinds)))]
        draw = kind.sample(rng)
        xy = self._free_spot(scene, footprint_radius(draw), rng)
        if xy is None:
            return None
        pantry = self.world.kitchen.locations[PANTRY].centre
        reach = point_at(self.arm, pantry, 0.0)
        self.arm.rest()
        body = self.world.add_object(kind, xy, float(rng.uniform(0, np.pi)), draw=draw)
        try:
            observed = self.world.observe()
            x = observed.X[-1].copy()
        finally:
            self.world.remove_object(body)
        return {"x": x, "kind": kind.name, "position": [round(float(v), 4) for v in xy],
                "sim_seconds": round(reach.sim_seconds, 3)}

    def close(self) -> None:
        self.world.close()
