"""The manager's view of the world: scenes, a held-out test set, pointing, pictures, the pantry.

``SimulatedKitchen`` is the real one (PyBullet world + Panda arm); tests may pass
any object with ``concepts``, ``feature_names``, ``next_scene``, ``point_at``
and ``test_set`` (:class:`Environment`). The optional abilities are Protocols,
checked once when the manager is made: :class:`SupportsLocations` and
:class:`SupportsViewpoint` (for descriptions), :class:`SupportsPictures` (numbered scene
pictures), :class:`SupportsFetch` (the pantry), :class:`KnowsRelevantFeatures`
(for scripted teachers) and :class:`HasTestScenes` (the task's test-set size).
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from bullet_world import Scene, World
from bullet_world.annotate import TeacherPicture, location_corners
from bullet_world.pantry import Spot, free_spots, glimpse, object_poses, replacement_spots, restore_poses
from bullet_world.viewpoint import Viewpoint
from bullet_world.world import HiddenObjectError
from dialog.language.pictures import annotate_scene, save_picture
from robot import Arm
from robot.gestures import point_at

PANTRY = "pantry"
FETCH_FREE_SPOTS = 2  # free pantry spots the robot tries (each costs one camera frame)
FETCH_SPILL_M = 0.06  # how far beside the pantry region a fetched object may stand
FETCH_REPLACEMENTS = 2  # objects of other concepts whose place a fetched object may take for a moment
REACH_CLEARANCE_RADIUS_M = 0.15  # objects this close to the reach keep the hand above their tops


class Environment(Protocol):
    concepts: tuple[str, ...]
    feature_names: tuple[str, ...]

    def next_scene(self, rng: np.random.Generator) -> Scene: ...

    def point_at(self, scene: Scene, object_index: int) -> dict: ...

    def test_set(self, n_scenes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]: ...


@runtime_checkable
class SupportsLocations(Protocol):
    """Named kitchen locations, for descriptions such as "on the stove"."""

    @property
    def locations(self) -> dict: ...


@runtime_checkable
class SupportsViewpoint(Protocol):
    """The teacher's viewpoint, for descriptions such as "at the back left"."""

    @property
    def viewpoint(self) -> Viewpoint: ...


@runtime_checkable
class SupportsPictures(Protocol):
    """Numbered pictures of a scene for the teacher."""

    def scene_picture(self, scene: Scene, path: str | Path, highlight: int | None = None) -> Path: ...


@runtime_checkable
class SupportsFetch(Protocol):
    """The pantry: fetch an example of a concept the teacher says is not in the scene."""

    def can_fetch(self, concept: str) -> bool: ...

    def fetch(self, scene: Scene, concept: str, rng: np.random.Generator) -> dict | None: ...


@runtime_checkable
class KnowsRelevantFeatures(Protocol):
    """The task's features that matter (ground truth, for scripted teachers only)."""

    @property
    def relevant_features(self) -> tuple[str, ...] | None: ...


@runtime_checkable
class HasTestScenes(Protocol):
    """How many held-out scenes the task's test set has."""

    test_scenes: int


DEFAULT_TEST_SCENES = 4  # for an environment that does not say


class SimulatedKitchen:
    """A PyBullet kitchen with the Panda: real rendering, perception, pointing and fetching."""

    def __init__(self, task: str = "pack-lunchbox", kitchen: str = "kitchen-1", seed: int = 0,
                 pictures: bool = False, objects_per_scene: int | None = None, joint_speed: float | None = None):
        self.joint_speed = joint_speed  # rad/s: the arm's gestures paced by a joint-speed limit (embodied costs)
        self.world = World(task=task, kitchen=kitchen, seed=seed, objects_per_scene=objects_per_scene)
        self.arm = Arm(self.world)
        self.concepts = self.world.task.concepts
        self.feature_names = self.world.feature_names
        self.test_scenes = self.world.task.test_scenes
        self.pictures = pictures
        self._scene_image = None  # (scene id, turned rgb, pixels of every object, location corner pixels)
        self._arm_out = False  # the arm pointed since the last scene: rest it before the world is observed again

    @property
    def locations(self) -> dict:
        return dict(self.world.kitchen.locations)

    @property
    def viewpoint(self) -> Viewpoint:
        """The teacher's: across the counter from the robot (left, right, front and back in words and pictures)."""
        return Viewpoint.of_kitchen(self.world.kitchen)

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
        result = point_at(self.arm, scene.positions[object_index], scene.tops[object_index], self.joint_speed)
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
        view = TeacherPicture(images, self.viewpoint)
        regions = {name: view.pixels(location_corners(location)) for name, location in self.locations.items()}
        self._scene_image = (scene.scene_id, view.rgb, view.pixels(scene.positions), regions)

    def picture_pixels(self, scene: Scene) -> tuple[np.ndarray, int, int]:
        """Each object's pixel (column, row) in the scene picture, and the picture's width and height (the page
        resolves a click on the picture to an object with these, dialog/web/teacher.py)."""
        if self._scene_image is None or self._scene_image[0] != scene.scene_id:
            self._capture(scene)
        _, rgb, pixels, _ = self._scene_image
        return np.asarray(pixels, dtype=float), int(rgb.shape[1]), int(rgb.shape[0])

    def scene_picture(self, scene: Scene, path: str | Path, highlight: int | None = None) -> Path:
        """Write the scene's camera image as the teacher sees it (the robot at the top), with every object's
        number (``highlight`` ringed) and the kitchen's locations, to ``path``."""
        if self._scene_image is None or self._scene_image[0] != scene.scene_id:
            self._capture(scene)
        _, rgb, pixels, regions = self._scene_image
        return save_picture(path, annotate_scene(rgb, pixels, range(1, len(pixels) + 1), highlight, regions))

    # -- the pantry -----------------------------------------------------------------
    def can_fetch(self, concept: str) -> bool:
        """Whether the task lets the robot fetch an example of ``concept`` from the kitchen's pantry."""
        allowed = getattr(self.world.task, "pantry_fetch", True)
        return bool(allowed) and PANTRY in self.world.kitchen.locations and concept in self.concepts

    def fetch(self, scene: Scene, concept: str, rng: np.random.Generator) -> dict | None:
        """Reach into the pantry for an example of ``concept``, show it to the camera, and put it back.

        The new object stands on a free spot of the pantry region the camera sees (or just beside it),
        else in the place of a scene object of another concept, set aside for the moment; the scene is
        left exactly as it was. Returns ``x`` (its observed feature row), ``kind``, ``position`` and
        ``sim_seconds``; when no spot works, ``x`` is None and ``reason`` says why. None when the task
        cannot fetch ``concept`` at all.
        """
        kinds = [k for k in getattr(self.world, "kinds", self.world.task.kinds) if k.concept == concept]
        if not kinds or not self.can_fetch(concept):
            return None
        kind = kinds[int(rng.integers(len(kinds)))]
        draw = kind.sample(rng)
        spots = self._fetch_spots(kind, draw, concept, rng)
        if not spots:
            return {"x": None, "kind": kind.name, "reason": "there is no room for it where the camera can see it"}
        reach = self._reach_over(spots[0].xy)
        for spot in spots:
            try:
                x = glimpse(self.world, kind, draw, spot)
            except HiddenObjectError:
                continue
            result = {"x": x, "kind": kind.name, "position": [round(float(v), 4) for v in spot.xy],
                      "sim_seconds": round(reach.sim_seconds, 3)}
            if spot.replaces is not None:
                result["replaced"] = self.world.objects[spot.replaces].kind.name
            return result
        return {"x": None, "kind": kind.name, "reason": "the camera could not see it wherever I put it",
                "sim_seconds": round(reach.sim_seconds, 3)}

    def _fetch_spots(self, kind, draw: dict, concept: str, rng: np.random.Generator) -> list[Spot]:
        """Spots to try, best first: free ones in the pantry, one just beside it, then places of objects
        of other concepts (nearest the pantry first)."""
        world, region = self.world, self.world.kitchen.locations[PANTRY]
        spots = free_spots(world, kind, draw, region, rng)[:FETCH_FREE_SPOTS]
        spots += free_spots(world, kind, draw, region, rng, spill_m=FETCH_SPILL_M)[:1]
        centre = np.asarray(region.centre[:2])
        others = sorted((i for i, obj in enumerate(world.objects) if obj.kind.concept != concept),
                        key=lambda i: float(np.linalg.norm(world.objects[i].xy - centre)))
        return spots + replacement_spots(world, kind, draw, others)[:FETCH_REPLACEMENTS]

    def _reach_over(self, xy: np.ndarray):
        """The reaching gesture: the hand above ``xy``, clear of the tallest object nearby, then back to rest.
        Any object the arm still nudged is put back where it stood."""
        world = self.world
        poses = object_poses(world)
        near = [obj.size[2] for obj in world.objects if np.linalg.norm(obj.xy - xy) <= REACH_CLEARANCE_RADIUS_M]
        reach = point_at(self.arm, np.array([xy[0], xy[1], 0.0]), max(near, default=0.0), self.joint_speed)
        self.arm.rest()
        restore_poses(world, poses)
        return reach

    def close(self) -> None:
        self.world.close()
