"""The simulated kitchen: one PyBullet client, a counter, objects drawn from a task's catalogue.

Scene dynamics (thesis §6.5.3): :meth:`World.new_scene` draws a new sample of
objects, places it and changes the lighting; :meth:`World.advance_states`
moves the objects of a task with states (prepare-lunch) one state on, in
place, leaving every other object where it was.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Protocol

import numpy as np
import pybullet as p

from bullet_world.bodies import BodyBuilder, PlacedObject, outline
from bullet_world.camera import Backdrop, Camera, CameraImages, Decal, Lighting
from bullet_world.catalogue import Kitchen, ObjectKind, Task, load_kitchen, load_task
from bullet_world.features import (
    environment_feature_catalogue,
    feature_matrix,
    object_feature_catalogue,
    object_feature_columns,
    robot_feature_catalogue,
)
from bullet_world.perception import measure_objects
from bullet_world.placement import Footprint, PlacementError, footprint_rows, place
from bullet_world.room import Piece
from bullet_world.scene import Scene, SceneTruth
from bullet_world.sensors import AmbientNoise, light_reading, weigh
from learning.errors import SceneError, SettingsError

PLACEMENT_RETRIES = 6   # new samples when one does not fit on the counter or hides an object from the camera


class HiddenObjectError(SceneError):
    """An object in the world is not visible to the camera."""


class Proprioceptor(Protocol):
    """What the world needs from an attached robot (robot.Arm satisfies it)."""

    body_id: int

    def proprioception(self) -> dict[str, float]: ...

    def rest(self, rng: np.random.Generator) -> None: ...


class World:
    """Owns one PyBullet client (DIRECT unless ``gui``); builds the kitchen and samples scenes.

    ``objects_per_scene`` overrides the task's count (up to its ``max_objects_per_scene``);
    ``sensor_noise`` adds seeded camera, scale, microphone and light-sensor noise; ``cache`` is where
    generated meshes and textures go (default: see :func:`bullet_world.datafiles.cache_dir`).
    """

    def __init__(self, task: str = "pack-lunchbox", kitchen: str = "kitchen-1", seed: int = 0, gui: bool = False,
                 objects_per_scene: int | None = None, sensor_noise: bool = True, cache=None):
        self.task: Task = load_task(task)
        self.kitchen: Kitchen = load_kitchen(kitchen)
        self.kinds: tuple[ObjectKind, ...] = self.task.kinds_in(self.kitchen.name)
        if objects_per_scene is not None:
            if not len(self.task.concepts) <= objects_per_scene <= self.task.max_objects_per_scene:
                raise SettingsError(f"objects_per_scene must be between {len(self.task.concepts)} and "
                                    f"{self.task.max_objects_per_scene} for task '{self.task.name}', "
                                    f"got {objects_per_scene}")
            self.task = replace(self.task, objects_per_scene=int(objects_per_scene))
        self.client = p.connect(p.GUI if gui else p.DIRECT)
        p.setGravity(0, 0, -9.81, physicsClientId=self.client)
        streams = np.random.SeedSequence([seed, 1]).spawn(4)
        self._scale_rng, self._camera_rng, self._light_rng, noise_rng = (np.random.default_rng(s) for s in streams)
        self.sensor_noise = sensor_noise
        self.ambient_noise = AmbientNoise(self.kitchen.ambient_noise, noise_rng)
        self.builder = BodyBuilder(self.client, cache)
        self.objects: list[PlacedObject] = []
        self._scene_count = 0
        self.stage = 0
        self.robot: Proprioceptor | None = None
        self.lighting = Lighting(tuple(self.kitchen.lighting["direction"]), 0.65, 0.6,
                                 tuple(self.kitchen.lighting["colour"]))
        self.counter_body = self._build_counter()
        under, above = self.kitchen.room_pieces()
        self.furniture: dict[int, str] = {}   # body -> name of every piece of the room (never an object)
        hidden = [self._build_piece(piece) for piece in under]
        floor = (hidden.pop(0), self.kitchen.room.floor_colour) if self.kitchen.room is not None else None
        flat = [piece for piece in above if self.kitchen.lies_on_worktop(piece)]
        decals = tuple(Decal(self._build_piece(piece), piece.shape, piece.centre[:2],
                             (piece.size[0] / 2, piece.size[1] / 2), piece.colour)
                       for piece in sorted(flat, key=lambda piece: piece.top))
        shown = tuple(self._build_piece(piece) for piece in above if piece not in flat)
        self.camera = Camera.from_config(self.kitchen.camera)
        length, depth, _ = self.kitchen.counter_size
        self.camera.set_backdrop(Backdrop(self.counter_body, self.kitchen.counter_centre, (length / 2, depth / 2),
                                          0.0, self.kitchen.counter_colour, tuple(hidden), floor, shown, decals))
        self.scene: Scene | None = None
        self.images: CameraImages | None = None

    # -- construction -------------------------------------------------------
    def _build_counter(self) -> int:
        length, depth, thickness = self.kitchen.counter_size
        half = [length / 2, depth / 2, thickness / 2]
        centre = [*self.kitchen.counter_centre, -thickness / 2]
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.client)
        visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=[*self.kitchen.counter_colour, 1],
                                     physicsClientId=self.client)
        return p.createMultiBody(0, shape, visual, centre, physicsClientId=self.client)

    def _build_piece(self, piece: Piece) -> int:
        """A static body for one piece of the room (see :mod:`bullet_world.room`)."""
        half = [s / 2 for s in piece.size]
        colour = [*piece.colour, 1.0]
        if piece.shape == "box":
            visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=colour, physicsClientId=self.client)
            shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.client) \
                if piece.collision else -1
        else:
            visual = p.createVisualShape(p.GEOM_CYLINDER, radius=half[0], length=piece.size[2], rgbaColor=colour,
                                         physicsClientId=self.client)
            shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=half[0], height=piece.size[2],
                                           physicsClientId=self.client) if piece.collision else -1
        body = p.createMultiBody(0, shape, visual, list(piece.centre), physicsClientId=self.client)
        self.furniture[body] = piece.name
        return body

    def attach_robot(self, robot: Proprioceptor) -> None:
        """Let the robot's proprioception join every observation's features."""
        self.robot = robot

    @property
    def feature_names(self) -> tuple[str, ...]:
        catalogue = object_feature_catalogue() + environment_feature_catalogue()
        if self.robot is not None:
            catalogue += robot_feature_catalogue()
        return tuple(info.name for info in catalogue)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- objects --------------------------------------------------------------
    @property
    def object_bodies(self) -> tuple[int, ...]:
        """PyBullet body ids of the scene objects, in object-number order."""
        return tuple(obj.body for obj in self.objects)

    def clear_objects(self) -> None:
        for obj in self.objects:
            p.removeBody(obj.body, physicsClientId=self.client)
        self.objects = []

    def add_object(self, kind: ObjectKind, xy, yaw: float, rng: np.random.Generator | None = None,
                   draw: dict | None = None) -> int:
        """Spawn one object of ``kind`` standing at ``xy``; its size, colour, mass (and state) come from
        ``draw`` or are drawn with ``rng``. Returns the body id; it joins the next observation."""
        if draw is None:
            if rng is None:
                raise ValueError("add_object needs either a generator or a draw")
            draw = kind.sample(rng)
        placed = self.builder.spawn(kind, draw, np.asarray(xy, dtype=float), yaw)
        self.objects.append(placed)
        return placed.body

    def remove_object(self, body: int) -> None:
        """Take one object out of the world and out of later observations."""
        index = self.object_bodies.index(body)
        p.removeBody(body, physicsClientId=self.client)
        del self.objects[index]

    def _draw_kinds(self, rng: np.random.Generator, count: int) -> list[ObjectKind]:
        """Stratified draw: concepts as evenly represented as the object count allows."""
        concepts = list(self.task.concepts)
        sequence = [concepts[i % len(concepts)] for i in range(count)]
        rng.shuffle(sequence)
        by_concept = {c: [k for k in self.kinds if k.concept == c] for c in concepts}
        return [by_concept[c][rng.integers(len(by_concept[c]))] for c in sequence]

    def _location_of(self, kind: ObjectKind, state: int):
        name = kind.state(state).location
        return self.kitchen.locations[name] if (self.task.place_at_locations and name) else None

    def _reserved(self) -> list:
        """Locations kept free of objects that don't belong there (when the task places by location)."""
        if not self.task.place_at_locations:
            return []
        used = {state.location for kind in self.kinds for state in kind.states if state.location}
        return [self.kitchen.locations[name] for name in sorted(used)]

    # -- scene dynamics -------------------------------------------------------
    def populate(self, rng: np.random.Generator, n_objects: int | None = None, stage: int | None = None,
                 rest_robot: bool = True) -> None:
        """Replace the objects with a fresh sample and change the lighting (no observation yet); an
        attached robot first moves to its rest pose (unless ``rest_robot`` is False).

        A kind with states is drawn in a random state (``stage`` None: every state equally likely, as
        in a representative test set) or in state ``min(stage, last)``.
        """
        self.clear_objects()
        if self.robot is not None and rest_robot:
            self.robot.rest(rng)
        count = self.task.objects_per_scene if n_objects is None else int(n_objects)
        self.lighting = Lighting.sample(self.kitchen.lighting, rng)
        self.stage = 0 if stage is None else int(stage)
        for attempt in range(PLACEMENT_RETRIES):  # a sample too bulky for the counter is drawn again
            kinds = self._draw_kinds(rng, count)
            states = [int(rng.integers(len(k.states))) if stage is None else min(stage, len(k.states) - 1)
                      for k in kinds]
            draws = [kind.sample(rng, state) for kind, state in zip(kinds, states)]
            footprints = [Footprint.from_tuple(outline(k, d)) for k, d in zip(kinds, draws)]
            locations = [self._location_of(k, s) for k, s in zip(kinds, states)]
            try:
                centres, yaws = place(footprints, self.kitchen, rng, locations, avoid=self._reserved())
                break
            except PlacementError:
                if attempt == PLACEMENT_RETRIES - 1:
                    raise
        for kind, draw, xy, yaw in zip(kinds, draws, centres, yaws):
            self.add_object(kind, xy, float(yaw), draw=draw)
        self._scene_count += 1

    def new_scene(self, rng: np.random.Generator, n_objects: int | None = None, stage: int | None = None) -> Scene:
        """A fresh sample of objects (see :meth:`populate`), observed. A sample in which the camera cannot
        see some object is drawn again."""
        for attempt in range(PLACEMENT_RETRIES):
            self.populate(rng, n_objects, stage)
            try:
                return self.observe()
            except HiddenObjectError:
                if attempt == PLACEMENT_RETRIES - 1:
                    raise
        raise AssertionError("unreachable")

    def advance_states(self, rng: np.random.Generator, probability: float | None = None) -> Scene:
        """One step of the task's state changes (pasta boxed -> in a pot -> in a bowl; fruit whole ->
        sliced): each object that has a next state moves on with ``probability`` (the task's
        ``state_change_probability`` by default) and is rebuilt, at its state's location when the task
        places by location. Every other object stays exactly where it was. Returns the new observation."""
        chance = self.task.state_change_probability if probability is None else probability
        changing = [i for i, obj in enumerate(self.objects)
                    if obj.draw.get("state", 0) < len(obj.kind.states) - 1 and rng.random() < chance]
        self.stage += 1
        if changing:
            keep = [i for i in range(len(self.objects)) if i not in changing]
            fixed = footprint_rows([Footprint.from_tuple(outline(self.objects[i].kind, self.objects[i].draw))
                                    for i in keep], [self.objects[i].xy for i in keep],
                                   [self.objects[i].yaw for i in keep])
            draws = {i: self.objects[i].kind.sample(rng, self.objects[i].draw.get("state", 0) + 1) for i in changing}
            footprints = [Footprint.from_tuple(outline(self.objects[i].kind, draws[i])) for i in changing]
            locations = [self._location_of(self.objects[i].kind, draws[i]["state"]) for i in changing]
            try:
                centres, yaws = place(footprints, self.kitchen, rng, locations, fixed=fixed, avoid=self._reserved())
            except PlacementError:  # the locations are full: the changed objects stand wherever there is room
                centres, yaws = place(footprints, self.kitchen, rng, None, fixed=fixed)
            for i, xy, yaw in zip(changing, centres, yaws):
                old = self.objects[i]
                p.removeBody(old.body, physicsClientId=self.client)
                self.objects[i] = self.builder.spawn(old.kind, draws[i], xy, float(yaw))
        self._scene_count += 1
        return self.observe()

    def start_lesson(self) -> None:
        """A new teaching session begins: the microphone's readings (behind the noise features) restart."""
        self.ambient_noise.restart()

    def change_lighting(self, rng: np.random.Generator) -> Scene:
        """A new lighting condition (direction, intensity, colour); the objects stay. Returns the observation."""
        self.lighting = Lighting.sample(self.kitchen.lighting, rng)
        self._scene_count += 1
        return self.observe()

    # -- observation ----------------------------------------------------------
    def render(self) -> CameraImages:
        """One camera frame (with sensor noise unless the world was made without it)."""
        self.images = self.camera.render(self.client, self.lighting,
                                         self._camera_rng if self.sensor_noise else None)
        return self.images

    def observe(self) -> Scene:
        """Render the camera, measure every object, read the other sensors, and build the feature matrix."""
        return self.observe_images(self.render())

    def observe_images(self, images: CameraImages) -> Scene:
        """Measure every object in ``images`` and build the scene (the part of :meth:`observe` after
        rendering)."""
        bodies = list(self.object_bodies)
        measurements = measure_objects(images.rgb, images.depth_buffer, images.segmentation,
                                       images.view_matrix, images.projection_matrix, bodies)
        hidden = [obj.kind.name for obj in self.objects if measurements[obj.body] is None]
        if hidden:
            raise HiddenObjectError(f"objects not visible to the camera: {', '.join(hidden)}")
        names = self.feature_names
        shared = self.ambient_noise.summary() if not self.sensor_noise else self._listen()
        shared |= light_reading(self.lighting, self._light_rng if self.sensor_noise else None)
        if self.robot is not None:
            shared |= self.robot.proprioception()
        seen = [measurements[b] for b in bodies]
        weights = [weigh(obj.draw["mass"], self._scale_rng) if self.sensor_noise else obj.draw["mass"]
                   for obj in self.objects]
        X = feature_matrix(object_feature_columns(seen, weights, self.kitchen), shared, names, len(bodies))
        poses = [p.getBasePositionAndOrientation(b, physicsClientId=self.client) for b in bodies]
        truth = SceneTruth(
            concepts=tuple(obj.kind.concept for obj in self.objects),
            kinds=tuple(obj.kind.name for obj in self.objects),
            body_ids=tuple(bodies),
            positions=np.array([pose[0] for pose in poses]).reshape(-1, 3),
            sizes=np.array([obj.size for obj in self.objects]).reshape(-1, 3),
            states=tuple(obj.state_name for obj in self.objects),
            masses=tuple(float(obj.draw["mass"]) for obj in self.objects),
            yaws=tuple(float(p.getEulerFromQuaternion(pose[1])[2]) for pose in poses),
        )
        self.scene = Scene(
            self._scene_count, X, names,
            np.array([m.centroid for m in seen]).reshape(-1, 3), np.array([m.height for m in seen]),
            np.array([m.mean_rgb for m in seen]).reshape(-1, 3), truth,
            outlines=np.array([m.box_corners for m in seen]).reshape(-1, 4, 2), stage=self.stage,
        )
        return self.scene

    def _listen(self) -> dict[str, float]:
        self.ambient_noise.listen()
        return self.ambient_noise.summary()
