"""The simulated kitchen: one PyBullet client, a counter, objects drawn from a task's catalogue."""

from __future__ import annotations

from typing import Protocol

import numpy as np
import pybullet as p

from bullet_world.camera import Camera, Lighting
from bullet_world.catalogue import Kitchen, ObjectKind, Task, load_kitchen, load_task
from bullet_world.features import (
    feature_row,
    object_feature_catalogue,
    object_feature_values,
    robot_feature_catalogue,
)
from bullet_world.perception import measure_objects
from bullet_world.scene import Scene, SceneTruth

WEIGHT_NOISE_KG = 0.005  # standard deviation of the scale under the counter


class Proprioceptor(Protocol):
    """What the world needs from an attached robot (robot.Arm satisfies it)."""

    body_id: int

    def proprioception(self) -> dict[str, float]: ...

    def rest(self, rng: np.random.Generator) -> None: ...


def footprint_radius(kind: ObjectKind, dims: dict[str, float]) -> float:
    """Radius of the circle that holds the object's footprint."""
    if kind.shape == "box":
        return 0.5 * float(np.hypot(dims["length"], dims["width"]))
    return dims["radius"]


def object_height(kind: ObjectKind, dims: dict[str, float]) -> float:
    return 2.0 * dims["radius"] if kind.shape == "sphere" else dims["height"]


class World:
    """Owns one PyBullet client (DIRECT unless ``gui``); builds the kitchen and samples scenes."""

    def __init__(self, task: str = "pack-lunchbox", kitchen: str = "kitchen-1", seed: int = 0, gui: bool = False):
        self.task: Task = load_task(task)
        self.kitchen: Kitchen = load_kitchen(kitchen)
        self.client = p.connect(p.GUI if gui else p.DIRECT)
        p.setGravity(0, 0, -9.81, physicsClientId=self.client)
        self.camera = Camera.from_config(self.kitchen.camera)
        self._noise_rng = np.random.default_rng([seed, 1])
        self._bodies: list[int] = []
        self._truth_rows: list[dict] = []
        self._scene_count = 0
        self.robot: Proprioceptor | None = None
        self.lighting = Lighting(tuple(self.kitchen.lighting["direction"]), 0.6, 0.6)
        self.counter_body = self._build_counter()
        self.scene: Scene | None = None

    # -- construction -------------------------------------------------------
    def _build_counter(self) -> int:
        length, depth, thickness = self.kitchen.counter_size
        half = [length / 2, depth / 2, thickness / 2]
        centre = [*self.kitchen.counter_centre, -thickness / 2]
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.client)
        visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=[*self.kitchen.counter_colour, 1],
                                     physicsClientId=self.client)
        return p.createMultiBody(0, shape, visual, centre, physicsClientId=self.client)

    def attach_robot(self, robot: Proprioceptor) -> None:
        """Let the robot's proprioception join every observation's features."""
        self.robot = robot

    @property
    def feature_names(self) -> tuple[str, ...]:
        catalogue = object_feature_catalogue() + (robot_feature_catalogue() if self.robot else ())
        return tuple(info.name for info in catalogue)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- scenes ---------------------------------------------------------------
    def clear_objects(self) -> None:
        for body in self._bodies:
            p.removeBody(body, physicsClientId=self.client)
        self._bodies, self._truth_rows = [], []

    def _place(self, radii: list[float], rng: np.random.Generator) -> np.ndarray:
        """Non-overlapping footprint centres inside the kitchen's object region (largest placed first)."""
        gap = self.kitchen.min_gap
        (x0, x1), (y0, y1) = self.kitchen.region_x, self.kitchen.region_y
        order = np.argsort(radii, kind="stable")[::-1]
        for _ in range(50):
            centres = np.zeros((len(radii), 2))
            placed: list[int] = []
            for index in order:
                radius = radii[index]
                for _ in range(300):
                    candidate = np.array([rng.uniform(x0 + radius, x1 - radius),
                                          rng.uniform(y0 + radius, y1 - radius)])
                    if all(np.linalg.norm(candidate - centres[j]) >= radius + radii[j] + gap for j in placed):
                        centres[index] = candidate
                        placed.append(index)
                        break
                else:
                    break
            if len(placed) == len(radii):
                return centres
        raise RuntimeError(f"cannot place {len(radii)} objects in kitchen '{self.kitchen.name}' "
                           f"without overlap; lower objects_per_scene or enlarge [object_region]")

    def _spawn(self, kind: ObjectKind, draw: dict, xy: np.ndarray, yaw: float) -> int:
        dims, rgba = draw["dimensions"], [*draw["colour"], 1.0]
        if kind.shape == "box":
            half = [dims["length"] / 2, dims["width"] / 2, dims["height"] / 2]
            collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.client)
            visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=self.client)
        elif kind.shape == "cylinder":
            collision = p.createCollisionShape(p.GEOM_CYLINDER, radius=dims["radius"], height=dims["height"],
                                               physicsClientId=self.client)
            visual = p.createVisualShape(p.GEOM_CYLINDER, radius=dims["radius"], length=dims["height"],
                                         rgbaColor=rgba, physicsClientId=self.client)
        else:
            collision = p.createCollisionShape(p.GEOM_SPHERE, radius=dims["radius"], physicsClientId=self.client)
            visual = p.createVisualShape(p.GEOM_SPHERE, radius=dims["radius"], rgbaColor=rgba,
                                         physicsClientId=self.client)
        position = [float(xy[0]), float(xy[1]), object_height(kind, dims) / 2]
        orientation = p.getQuaternionFromEuler([0, 0, yaw])
        return p.createMultiBody(draw["mass"], collision, visual, position, orientation, physicsClientId=self.client)

    @property
    def object_bodies(self) -> tuple[int, ...]:
        """PyBullet body ids of the scene objects, in object-number order."""
        return tuple(self._bodies)

    def add_object(self, kind: ObjectKind, xy, yaw: float, rng: np.random.Generator | None = None,
                   draw: dict | None = None) -> int:
        """Spawn one object of ``kind`` standing at ``xy``; its size, colour and mass come from
        ``draw`` or are drawn with ``rng``. Returns the body id; it joins the next observation."""
        if draw is None:
            if rng is None:
                raise ValueError("add_object needs either a generator or a draw")
            draw = kind.sample(rng)
        body = self._spawn(kind, draw, np.asarray(xy, dtype=float), yaw)
        dims = draw["dimensions"]
        size = [dims["length"], dims["width"]] if kind.shape == "box" else [2 * dims["radius"]] * 2
        self._bodies.append(body)
        self._truth_rows.append({"kind": kind.name, "concept": kind.concept, "mass": draw["mass"],
                                 "size": [*size, object_height(kind, dims)]})
        return body

    def remove_object(self, body: int) -> None:
        """Take one object out of the world and out of later observations."""
        index = self._bodies.index(body)
        p.removeBody(body, physicsClientId=self.client)
        del self._bodies[index], self._truth_rows[index]

    def _draw_kinds(self, rng: np.random.Generator) -> list[ObjectKind]:
        """Stratified draw: concepts as evenly represented as the object count allows."""
        concepts = list(self.task.concepts)
        count = self.task.objects_per_scene
        sequence = [concepts[i % len(concepts)] for i in range(count)]
        rng.shuffle(sequence)
        by_concept = {c: [k for k in self.task.kinds if k.concept == c] for c in concepts}
        return [by_concept[c][rng.integers(len(by_concept[c]))] for c in sequence]

    def new_scene(self, rng: np.random.Generator) -> Scene:
        """Replace the objects with a fresh sample, change the lighting, and observe."""
        self.clear_objects()
        if self.robot is not None:
            self.robot.rest(rng)
        kinds = self._draw_kinds(rng)
        draws = [kind.sample(rng) for kind in kinds]
        centres = self._place([footprint_radius(k, d["dimensions"]) for k, d in zip(kinds, draws)], rng)
        for kind, draw, xy in zip(kinds, draws, centres):
            self.add_object(kind, xy, float(rng.uniform(0, np.pi)), draw=draw)
        self.lighting = Lighting.sample(self.kitchen.lighting, rng)
        self._scene_count += 1
        return self.observe()

    def observe(self) -> Scene:
        """Render the camera, measure every object, and build the scene's feature matrix."""
        images = self.camera.render(self.client, self.lighting)
        measurements = measure_objects(images.rgb, images.depth_buffer, images.segmentation,
                                       images.view_matrix, images.projection_matrix, self._bodies)
        names = self.feature_names
        robot_values = self.robot.proprioception() if self.robot else {}
        rows, positions, tops, colours = [], [], [], []
        for body, truth in zip(self._bodies, self._truth_rows):
            measured = measurements[body]
            if measured is None:
                raise RuntimeError(f"object {truth['kind']} (body {body}) is not visible to the camera")
            weight = truth["mass"] + self._noise_rng.normal(0.0, WEIGHT_NOISE_KG)
            values = object_feature_values(measured, weight) | robot_values
            rows.append(feature_row(values, names))
            positions.append(measured.centroid)
            tops.append(measured.height)
            colours.append(measured.mean_rgb)
        true_positions = np.array([p.getBasePositionAndOrientation(b, physicsClientId=self.client)[0]
                                   for b in self._bodies])
        truth = SceneTruth(
            concepts=tuple(t["concept"] for t in self._truth_rows),
            kinds=tuple(t["kind"] for t in self._truth_rows),
            body_ids=tuple(self._bodies),
            positions=true_positions.reshape(-1, 3),
            sizes=np.array([t["size"] for t in self._truth_rows]),
        )
        X = np.vstack(rows) if rows else np.zeros((0, len(names)))
        self.scene = Scene(self._scene_count, X, names, np.array(positions).reshape(-1, 3), np.array(tops),
                           np.array(colours).reshape(-1, 3), truth)
        return self.scene
