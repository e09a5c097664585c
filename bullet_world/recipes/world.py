"""Recipe scenes in the simulated kitchen: a household's objects, a scripted teacher, observations.

``RecipeWorld`` builds one kitchen (``World``) with the household of that
kitchen (``[recipe_scenes]`` of the task file, see ``recipe_setup``): each
object is drawn once, so the same pot and bowls appear in every demonstration,
as in one real home. It then

* arranges the objects inside their semantic locations (``recipe_layout``),
  swept systematically across each location over a series of demonstrations;
* switches between the task's lighting conditions;
* plays the teacher: for every recipe step the teacher's hand (not simulated)
  lifts the step's object out of the scene and sets it down inside the end
  location, the physics settles, and the camera looks before and after;
* observes through the real pipeline: the world's camera (TinyRenderer RGB-D
  and segmentation with sensor noise), then ``perception.measure_objects``. Each observation lists the perceived
  objects in a random order, so a learner cannot use the simulator's body ids
  to tell which object moved; rows are matched by ``recipe_tracking``.

Appearance is (r, g, b, length, width, height); location is the bounding-box
centre relative to the robot (thesis §4.3.1): x forward from the robot base,
y to its left, z up. ``truth`` in an observation is hidden ground truth for
scripted evaluation only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as p

from bullet_world.kitchen import Location
from bullet_world.perception import ObjectMeasurement, measure_objects
from bullet_world.recipes.layout import Arrangement, Placer, object_radius_and_height
from bullet_world.recipes.setup import ELSEWHERE, load_recipe_setup
from bullet_world.world import World
from learning.errors import SceneError, SettingsError

APPEARANCE_NAMES = ("r", "g", "b", "length", "width", "height")
LOCATION_NAMES = ("x", "y", "z")


@dataclass(frozen=True)
class RecipeTruth:
    """Hidden ground truth of an observation, row by row: kind, recipe role ("" for none), body id."""

    kinds: tuple[str, ...]
    roles: tuple[str, ...]
    body_ids: tuple[int, ...]

    def row_of_role(self, role: str) -> int:
        return self.roles.index(role)


@dataclass(frozen=True, eq=False)
class RecipeObservation:
    """What the camera saw: one row per perceived object, in an arbitrary order."""

    appearance: np.ndarray                 # (n, 6) r, g, b, length, width, height
    locations: np.ndarray                  # (n, 3) bounding-box centre relative to the robot
    measurements: tuple[ObjectMeasurement, ...]  # world-frame measurements (for grasping)
    lighting: str
    truth: RecipeTruth


@dataclass(frozen=True, eq=False)
class DemonstratedStep:
    """The teacher's demonstration of one recipe step: observations before and after."""

    object: str
    start: str
    end: str
    before: RecipeObservation
    after: RecipeObservation


@dataclass(frozen=True, eq=False)
class RecipeDemonstration:
    """One demonstration of the whole recipe: its number, arrangement, lighting and steps."""

    number: int
    layout: int
    lighting: str
    steps: tuple[DemonstratedStep, ...]


class RecipeWorld:
    """One kitchen with its household, a scripted teacher and the camera (see the module doc).

    ``steps`` is the recipe as plain (object, start, end) triples.
    """

    def __init__(self, steps: Sequence[tuple[str, str, str]], task: str = "serve-pasta",
                 kitchen: str = "kitchen-1", seed: int = 0):
        self.setup = load_recipe_setup(task)
        self.world = World(task=task, kitchen=kitchen, seed=seed)
        try:
            self._build(steps, seed)
        except Exception:
            self.world.close()
            raise

    def _build(self, steps: Sequence[tuple[str, str, str]], seed: int) -> None:
        self.steps = tuple((str(o), str(s), str(e)) for o, s, e in steps)
        self.kitchen = self.world.kitchen
        self.household = self.setup.household_for(self.kitchen)
        roles = self.household.roles()
        for obj, start, _end in self.steps:
            if obj not in roles:
                raise SceneError(f"household '{self.household.name}' of task '{self.setup.task}' has no object "
                                 f"playing '{obj}'; roles it has: {', '.join(sorted(roles)) or 'none'}")
            if roles[obj].at != start:
                raise SceneError(f"household '{self.household.name}': the {obj} lives at '{roles[obj].at}', but "
                                 f"the recipe takes it from '{start}'")
        used = sorted({s for _, s, _ in self.steps} | {e for _, _, e in self.steps}
                      | {item.at for item in self.household.objects} - {ELSEWHERE})
        missing = [name for name in used if name not in self.kitchen.locations]
        if missing:
            raise SceneError(f"kitchen '{self.kitchen.name}' has no location {missing[0]!r}; it has: "
                             f"{', '.join(sorted(self.kitchen.locations))}")
        recipe_locations = tuple(dict.fromkeys(name for step in self.steps for name in step[1:]))
        self.placer = Placer(self.kitchen, self.setup, recipe_locations)
        kinds = {kind.name: kind for kind in self.world.task.kinds}
        draw_rng = np.random.default_rng([seed, 4, 7])
        self._kinds = [kinds[item.kind] for item in self.household.objects]
        self._draws = [kind.sample(draw_rng) for kind in self._kinds]
        self._homes = [item.at for item in self.household.objects]
        self._roles = [item.role for item in self.household.objects]
        sizes = [object_radius_and_height(kind, draw) for kind, draw in zip(self._kinds, self._draws)]
        self._radii = [radius for radius, _ in sizes]
        self._heights = [height for _, height in sizes]
        self._step_objects = [(self._roles.index(obj), end) for obj, _, end in self.steps]
        first = self.placer.arrangement(self._homes, self._radii, self._step_objects, np.random.default_rng([seed, 5]))
        self.bodies = tuple(self.world.add_object(kind, xy, float(yaw), draw=draw)
                            for kind, draw, xy, yaw in zip(self._kinds, self._draws, first.xy, first.yaw))
        self.arrangement = first
        self.lighting_name = next(iter(self.setup.lighting))
        self.set_lighting(self.lighting_name)
        self._settle()

    # ------------------------------------------------------------------ frames
    @property
    def _base(self) -> tuple[np.ndarray, float]:
        return np.asarray(self.kitchen.robot_base, dtype=float), float(self.kitchen.robot_yaw)

    def to_robot_frame(self, points: np.ndarray) -> np.ndarray:
        """World (x, y, z) rows -> relative to the robot base (x forward, y left, z up)."""
        base, yaw = self._base
        c, s = np.cos(yaw), np.sin(yaw)
        offset = np.atleast_2d(np.asarray(points, dtype=float)) - base
        return np.column_stack([c * offset[:, 0] + s * offset[:, 1], -s * offset[:, 0] + c * offset[:, 1],
                                offset[:, 2]])

    def to_world_frame(self, points: np.ndarray) -> np.ndarray:
        """Inverse of ``to_robot_frame``."""
        base, yaw = self._base
        c, s = np.cos(yaw), np.sin(yaw)
        local = np.atleast_2d(np.asarray(points, dtype=float))
        return np.column_stack([c * local[:, 0] - s * local[:, 1], s * local[:, 0] + c * local[:, 1],
                                local[:, 2]]) + base

    def region(self, name: str) -> Location:
        """The kitchen's true region of a semantic location (for evaluation and the benchmark)."""
        return self.kitchen.locations[name]

    # -------------------------------------------------------------- arranging
    def set_lighting(self, name: str) -> None:
        if name not in self.setup.lighting:
            raise SettingsError(f"unknown lighting {name!r}; accepted: {', '.join(self.setup.lighting)}")
        self.lighting_name = name
        self.world.lighting = self.setup.lighting[name]

    def new_arrangement(self, rng: np.random.Generator, around: Arrangement | None = None) -> Arrangement:
        """A feasible arrangement: near the spots of ``around`` where possible, else drawn uniformly."""
        return self.placer.arrangement(self._homes, self._radii, self._step_objects, rng, around)

    def arrange(self, arrangement: Arrangement) -> None:
        """Put every object at its start spot and let the physics settle."""
        for index, body in enumerate(self.bodies):
            self._put(body, index, arrangement.xy[index], arrangement.yaw[index])
        self.arrangement = arrangement
        self._settle()

    def _put(self, body: int, index: int, xy, yaw: float) -> None:
        position = [float(xy[0]), float(xy[1]), self._heights[index] / 2 + 0.001]
        orientation = p.getQuaternionFromEuler([0.0, 0.0, float(yaw)])
        p.resetBasePositionAndOrientation(body, position, orientation, physicsClientId=self.world.client)
        p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=self.world.client)

    def _settle(self) -> None:
        for _ in range(self.setup.settle_steps):
            p.stepSimulation(physicsClientId=self.world.client)

    # -------------------------------------------------------------- observing
    def observe(self, rng: np.random.Generator) -> RecipeObservation:
        """Render, measure every object, and list the perceived objects in a random order."""
        images = self.world.render()
        measured = measure_objects(images.rgb, images.depth_buffer, images.segmentation, images.view_matrix,
                                   images.projection_matrix, self.bodies)
        visible = [i for i, body in enumerate(self.bodies) if measured[body] is not None]
        order = [visible[k] for k in rng.permutation(len(visible))]
        rows = [measured[self.bodies[i]] for i in order]
        appearance = np.array([[*m.mean_rgb, m.length, m.width, m.height] for m in rows]).reshape(-1, 6)
        centres = np.array([m.centroid for m in rows]).reshape(-1, 3)
        truth = RecipeTruth(tuple(self._kinds[i].name for i in order), tuple(self._roles[i] for i in order),
                            tuple(self.bodies[i] for i in order))
        return RecipeObservation(appearance, self.to_robot_frame(centres), tuple(rows), self.lighting_name, truth)

    def true_position(self, body: int) -> np.ndarray:
        """The simulator's pose of a body: ground truth for evaluation only."""
        return np.asarray(p.getBasePositionAndOrientation(body, physicsClientId=self.world.client)[0])

    # ------------------------------------------------------------ the teacher
    def demonstrate(self, count: int, rng: np.random.Generator) -> list[RecipeDemonstration]:
        """``count`` demonstrations of the recipe (thesis §4.3.2).

        The L arrangements of one sweep (``layouts`` in the task file, see
        ``recipe_layout``) are shown under the first lighting condition, then the
        same L under the next condition, and so on; more demonstrations than
        that start a new sweep.
        """
        if not isinstance(count, (int, np.integer)) or count < 1:
            raise SettingsError(f"the number of demonstrations must be a whole number >= 1, got {count!r}")
        conditions = list(self.setup.lighting)
        per_sweep = self.setup.layouts
        targets: list[Arrangement] = []
        layouts: list[Arrangement] = []
        demonstrations = []
        for number in range(count):
            round_, within = divmod(number, per_sweep * len(conditions))
            layout = round_ * per_sweep + within % per_sweep
            while len(layouts) <= layout:
                if len(targets) == len(layouts):
                    targets.extend(self.placer.sweep(self._homes, self._radii, self._step_objects, per_sweep, rng))
                layouts.append(self.new_arrangement(rng, targets[len(layouts)]))
            lighting = conditions[within // per_sweep]
            demonstrations.append(self.demonstrate_once(number + 1, layout, layouts[layout], lighting, rng))
        return demonstrations

    def demonstrate_once(self, number: int, layout: int, arrangement: Arrangement, lighting: str,
                         rng: np.random.Generator) -> RecipeDemonstration:
        """The teacher performs every step once, from ``arrangement``, under ``lighting``."""
        self.set_lighting(lighting)
        self.arrange(arrangement)
        steps = []
        for number_in_recipe, ((obj, start, end), (index, _)) in enumerate(zip(self.steps, self._step_objects)):
            before = self.observe(rng)
            self._put(self.bodies[index], index, arrangement.end_xy[number_in_recipe],
                      arrangement.end_yaw[number_in_recipe])
            self._settle()
            steps.append(DemonstratedStep(obj, start, end, before, self.observe(rng)))
        return RecipeDemonstration(number, layout, lighting, tuple(steps))

    def close(self) -> None:
        self.world.close()

    def __enter__(self) -> RecipeWorld:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
