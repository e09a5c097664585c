"""Where a recipe scene's objects stand: feasible spots, fresh arrangements and small perturbations.

A spot for an object of footprint radius r is feasible when

* its centre lies inside the semantic location's region shrunk by the margin
  (or, for ``"elsewhere"``, inside the kitchen's object region -- its box,
  reach and excluded bearings -- and at least r clear of every region the
  recipe uses),
* its centre is within the arm's top-down grasping reach (an annulus around
  the robot base, ``reach`` in the task file), and
* its footprint keeps ``min_gap`` from every other object's footprint.

Arrangements for a series of demonstrations follow a sweep (thesis §4.3.2:
"systematically perturbed to yield a small change in edit distance between
any two adjacent task demonstrations; nonetheless, the demonstrations had
significant variance over the course of the entire set"): each location is
cut into a grid of cells visited in serpentine order, one cell further per
demonstration, so an object moves to a neighbouring cell each time and visits
the whole location over the series; objects sharing a location start at
different cells, and every object turns a little each time. Each spot is drawn
around its cell with ``jitter_m`` (and ``yaw_jitter``); objects kept
"elsewhere" stay near one random spot. A spot that is not feasible near its
target is drawn afresh, uniformly. All randomness comes from the generator
passed in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bullet_world.bodies import outline
from bullet_world.catalogue import ObjectKind
from bullet_world.kitchen import Kitchen
from bullet_world.meshes import true_size
from bullet_world.placement import Footprint, PlacementError
from bullet_world.recipes.setup import ELSEWHERE, RecipeSceneSetup

LOCAL_TRIES = 40     # proposals around a target spot before placing an object afresh
FRESH_TRIES = 400    # uniform proposals per object
RESTARTS = 60        # whole-arrangement restarts before giving up


def object_radius_and_height(kind: ObjectKind, draw: dict) -> tuple[float, float]:
    """Radius of the circle holding a drawn object's footprint, and its height (metres)."""
    radius = Footprint.from_tuple(outline(kind, draw)).radius
    return float(radius), float(true_size(kind.state(draw.get("state", 0)), draw["dimensions"])[2])


@dataclass(frozen=True)
class Arrangement:
    """Where every object stands (world x, y and yaw), plus the teacher's put-down spot for each step."""

    xy: np.ndarray            # (n, 2)
    yaw: np.ndarray           # (n,)
    end_xy: np.ndarray        # (steps, 2): where the teacher puts the object of each recipe step
    end_yaw: np.ndarray       # (steps,)


class Placer:
    """Feasibility and sampling of object spots in one kitchen (see the module doc)."""

    def __init__(self, kitchen: Kitchen, setup: RecipeSceneSetup, recipe_locations: tuple[str, ...]):
        self.kitchen = kitchen
        self.setup = setup
        self.recipe_locations = tuple(recipe_locations)
        self.base = np.asarray(kitchen.robot_base[:2], dtype=float)

    def bounds(self, at: str, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corner of the box that may hold the centre of an object at ``at``."""
        if at == ELSEWHERE:
            low = np.array([self.kitchen.region_x[0], self.kitchen.region_y[0]]) + radius
            high = np.array([self.kitchen.region_x[1], self.kitchen.region_y[1]]) - radius
            return low, high
        location = self.kitchen.locations[at]
        centre = np.asarray(location.centre[:2], dtype=float)
        half = np.asarray(location.half_size, dtype=float) - self.setup.region_margin
        return centre - half, centre + half

    def feasible(self, at: str, xy: np.ndarray, radius: float, others: list[tuple[np.ndarray, float]]) -> bool:
        low, high = self.bounds(at, radius)
        if np.any(xy < low) or np.any(xy > high):
            return False
        distance = float(np.linalg.norm(xy - self.base))
        if not self.setup.reach[0] <= distance <= self.setup.reach[1]:
            return False
        if at == ELSEWHERE and (not self.kitchen.in_object_region(xy)[0]
                                or any(self._near_region(name, xy, radius) for name in self.recipe_locations)):
            return False
        gap = self.setup.min_gap
        return all(np.linalg.norm(xy - other) >= radius + other_radius + gap for other, other_radius in others)

    def _near_region(self, name: str, xy: np.ndarray, radius: float) -> bool:
        location = self.kitchen.locations[name]
        offset = np.abs(xy - np.asarray(location.centre[:2]))
        return bool(np.all(offset <= np.asarray(location.half_size) + radius))

    def sample(self, at: str, radius: float, others: list[tuple[np.ndarray, float]], rng: np.random.Generator,
               around: np.ndarray | None = None) -> np.ndarray | None:
        """A feasible spot: a perturbation of ``around`` if one is found, else a uniform draw; None if neither."""
        if around is not None:
            for _ in range(LOCAL_TRIES):
                candidate = around + rng.normal(0.0, self.setup.jitter_m, 2)
                if self.feasible(at, candidate, radius, others):
                    return candidate
        low, high = self.bounds(at, radius)
        if np.any(low > high):
            return None
        for _ in range(FRESH_TRIES):
            candidate = rng.uniform(low, high)
            if self.feasible(at, candidate, radius, others):
                return candidate
        return None

    def sweep(self, homes: list[str], radii: list[float], steps: list[tuple[int, str]], count: int,
              rng: np.random.Generator) -> list[Arrangement]:
        """Target arrangements for ``count`` demonstrations (see the module doc); not yet checked for overlaps.

        Each location is cut into a grid of about ``count`` cells, visited in
        serpentine order from a random corner; objects sharing a location start
        at different cells, so they do not compete for the same spot.
        """
        users = [*homes, *(end for _, end in steps)]
        sizes = [*radii, *(radii[index] for index, _ in steps)]
        cells = {at: self._serpentine(at, max(r for u, r in zip(users, sizes) if u == at), count, rng)
                 for at in dict.fromkeys(users) if at != ELSEWHERE}
        paths = []
        for number, (at, radius) in enumerate(zip(users, sizes)):
            if at == ELSEWHERE:  # a distractor kept elsewhere stays near one spot
                spot = self.sample(at, radius, [], rng)
                spot = np.mean(self.bounds(at, radius), axis=0) if spot is None else spot
                paths.append(np.repeat(spot[None], count, axis=0))
                continue
            sharing = [i for i, user in enumerate(users) if user == at]
            shift = sharing.index(number) * len(cells[at]) // len(sharing)
            paths.append(np.array([cells[at][(shift + j) % len(cells[at])] for j in range(count)]))
        starts, ends = paths[:len(homes)], paths[len(homes):]
        turn_start, turn_end = rng.uniform(0, np.pi, len(homes)), rng.uniform(0, np.pi, len(steps))
        targets = []
        for j in range(count):
            turn = j * np.pi / count
            targets.append(Arrangement(np.array([path[j] for path in starts]).reshape(-1, 2),
                                       np.mod(turn_start + turn, np.pi),
                                       np.array([path[j] for path in ends]).reshape(-1, 2),
                                       np.mod(turn_end + turn, np.pi)))
        return targets

    def _serpentine(self, at: str, radius: float, count: int, rng: np.random.Generator) -> list[np.ndarray]:
        """Spots at the cells of a grid over the location, in serpentine order from a random corner."""
        low, high = self.bounds(at, radius)
        size = np.maximum(high - low, 1e-6)
        rows = 1 if count < 4 else 2
        columns = int(np.ceil(count / rows))
        long_axis = int(np.argmax(size))
        cells = []
        for row in range(rows):
            order = range(columns) if row % 2 == 0 else reversed(range(columns))
            for column in order:
                fraction = np.empty(2)
                fraction[long_axis] = (column + 0.5) / columns
                fraction[1 - long_axis] = (row + 0.5) / rows
                cells.append((fraction, 1.0 / np.where(np.arange(2) == long_axis, columns, rows)))
        flip = rng.random(2) < 0.5
        spots = []
        for fraction, cell in cells:
            fraction = np.where(flip, 1.0 - fraction, fraction)
            spot = low + fraction * size
            if not self.feasible(at, spot, radius, []):
                for _ in range(LOCAL_TRIES):
                    candidate = low + (fraction + (rng.random(2) - 0.5) * cell) * size
                    if self.feasible(at, candidate, radius, []):
                        spot = candidate
                        break
            spots.append(spot)
        return spots

    def arrangement(self, homes: list[str], radii: list[float], steps: list[tuple[int, str]],
                    rng: np.random.Generator, previous: Arrangement | None = None) -> Arrangement:
        """Start spots for every object and put-down spots for every step, near ``previous`` if given.

        ``steps`` lists (object index, end location) in recipe order; each put-down
        spot avoids the objects still standing and those already put down.
        """
        for _ in range(RESTARTS):
            result = self._try_arrangement(homes, radii, steps, rng, previous)
            if result is not None:
                return result
        raise PlacementError(
            f"cannot arrange {len(homes)} objects without overlap in kitchen '{self.kitchen.name}' within reach "
            f"{list(self.setup.reach)} m; accepted: fewer or smaller objects per location, or larger regions")

    def _try_arrangement(self, homes, radii, steps, rng, previous) -> Arrangement | None:
        count = len(homes)
        xy = np.zeros((count, 2))
        placed: list[int] = []
        for index in np.argsort(radii, kind="stable")[::-1]:
            around = None if previous is None else previous.xy[index]
            spot = self.sample(homes[index], radii[index], [(xy[j], radii[j]) for j in placed], rng, around)
            if spot is None:
                return None
            xy[index] = spot
            placed.append(int(index))
        yaw = self._yaws(count, rng, None if previous is None else previous.yaw)
        standing = dict.fromkeys(range(count))
        end_xy = np.zeros((len(steps), 2))
        for number, (index, end) in enumerate(steps):
            standing.pop(index, None)
            others = [(xy[j], radii[j]) for j in standing] + [(end_xy[k], radii[steps[k][0]]) for k in range(number)]
            around = None if previous is None else previous.end_xy[number]
            spot = self.sample(end, radii[index], others, rng, around)
            if spot is None:
                return None
            end_xy[number] = spot
        end_yaw = self._yaws(len(steps), rng, None if previous is None else previous.end_yaw)
        return Arrangement(xy, yaw, end_xy, end_yaw)

    def _yaws(self, count: int, rng: np.random.Generator, previous: np.ndarray | None) -> np.ndarray:
        if previous is None:
            return rng.uniform(0.0, np.pi, count)
        return np.mod(previous + rng.normal(0.0, self.setup.yaw_jitter, count), np.pi)
