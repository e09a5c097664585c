"""Where things stand in a generated kitchen: the worktop, the arm, the five locations, the object region and
the ceiling camera, drawn from :class:`~bullet_world.generation.distributions.Distributions`.

The worktop is centred on the origin with its front edge at y = -depth / 2; the arm stands at that edge and
faces +y (turned a little). Every value is rounded to what the kitchen file records *before* it is checked,
so the file holds exactly what passed."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bullet_world.datafiles import DataFileError
from bullet_world.generation.distributions import Distributions, Family
from bullet_world.kitchen import INTEREST_POINTS, Kitchen, Location


def metres(value: float) -> float:
    """A length as a kitchen file records it (millimetres)."""
    return round(float(value), 3)


@dataclass(frozen=True)
class Layout:
    """The drawn geometry of one kitchen (world frame, metres)."""

    family: Family
    length: float
    depth: float
    worktop_height: float
    base: tuple[float, float]
    yaw_degrees: float
    locations: dict[str, Location]     # in the order the arc holds them, from the arm's right to its left
    region: dict                       # the kitchen's [object_region]
    camera: dict                       # the kitchen's [camera]

    def kitchen(self, distributions: Distributions) -> Kitchen:
        """A bare :class:`Kitchen` of this layout, for its geometry (reach, object region)."""
        return bare_kitchen(self.length, self.depth, self.base, self.yaw_degrees, self.region, self.locations,
                            distributions.worktop["thickness"])


def bare_kitchen(length, depth, base, yaw_degrees, region, locations, thickness) -> Kitchen:
    return Kitchen(name="draft", counter_size=(length, depth, thickness), counter_centre=(0.0, 0.0),
                   counter_colour=(0.5, 0.5, 0.5), robot_base=(*base, 0.0), robot_yaw=math.radians(yaw_degrees),
                   region_x=tuple(region["x"]), region_y=tuple(region["y"]), min_gap=region["min_gap"], camera={},
                   lighting={}, locations=locations, min_reach=region["min_reach"], max_reach=region["max_reach"],
                   max_bearing=region["max_bearing_degrees"])


def draw_family(distributions: Distributions, rng: np.random.Generator) -> Family:
    weights = np.array([family.weight for family in distributions.families])
    return distributions.families[int(rng.choice(len(weights), p=weights / weights.sum()))]


def draw_layout(distributions: Distributions, family: Family, rng: np.random.Generator, seed: int) -> Layout:
    """The worktop, the arm, the locations, the object region and the camera of one kitchen."""
    ranges, reach = family.ranges, distributions.reach
    length, depth = metres(rng.uniform(*ranges["length"])), metres(rng.uniform(*ranges["depth"]))
    height = metres(rng.uniform(*distributions.worktop["height"]))
    base = (metres(rng.uniform(*ranges["robot_offset"])), metres(-depth / 2 + distributions.worktop["base_inset"]))
    yaw = round(90.0 + float(rng.uniform(*ranges["turn_degrees"])), 1)
    forward = np.array([math.cos(math.radians(yaw)), math.sin(math.radians(yaw))])
    ends, front, back = reach["region_inset"]
    ahead = rng.uniform(*reach["focus_ahead"])
    region = {"x": [metres(-length / 2 + ends), metres(length / 2 - ends)],
              "y": [metres(-depth / 2 + front), metres(depth / 2 - back)],
              "min_reach": reach["min_reach"], "max_reach": reach["max_reach"],
              "max_bearing_degrees": reach["max_bearing_degrees"],
              "focus": [metres(base[0] + ahead * forward[0]), metres(base[1] + ahead * forward[1])],
              "focus_spread": reach["focus_spread"], "min_gap": reach["min_gap"]}
    locations = _draw_locations(distributions, family, rng, length, depth, base, yaw, region, seed)
    layout = Layout(family, length, depth, height, base, yaw, locations, region, {})
    kitchen = layout.kitchen(distributions)
    return Layout(family, length, depth, height, base, yaw, locations, region,
                  _camera(distributions.camera, kitchen))


def _draw_locations(distributions, family, rng, length, depth, base, yaw, region, seed) -> dict[str, Location]:
    """Five locations in an arc around the arm, in a drawn order, until one arrangement passes every check."""
    reach = distributions.reach
    span, jitter = family.bearing_span, family.bearing_jitter
    for _ in range(reach["tries"]):
        order = [INTEREST_POINTS[i] for i in rng.permutation(len(INTEREST_POINTS))]
        bearings = np.linspace(-span, span, len(order)) + rng.uniform(-jitter, jitter, len(order))
        locations = {}
        for location_name, bearing in zip(order, bearings):
            half = tuple(round(float(rng.uniform(*reach["half_size"][axis])), 2) for axis in (0, 1))
            diagonal = math.hypot(*half)
            near, far = reach["location_reach"][0] + diagonal, reach["location_reach"][1] - diagonal
            distance = rng.uniform(near, max(near, far))
            angle = math.radians(yaw + bearing)
            centre = (round(base[0] + distance * math.cos(angle), 2), round(base[1] + distance * math.sin(angle), 2))
            locations[location_name] = Location(location_name, (*centre, 0.0), half)
        if _arrangement_fits(locations, distributions, length, depth, base, yaw, region):
            return locations
    raise DataFileError(f"{distributions.path} [reach]: seed {seed}: no arrangement of the five locations fitted "
                        f"the '{family.name}' worktop in {reach['tries']} tries; widen 'location_reach' or "
                        f"'location_bearing_degrees', or narrow 'half_size'")


def corners(location: Location) -> np.ndarray:
    (cx, cy, _), (hx, hy) = location.centre, location.half_size
    return np.array([[cx - hx, cy - hy], [cx + hx, cy - hy], [cx + hx, cy + hy], [cx - hx, cy + hy]])


def location_problem(location: Location, distributions: Distributions, length, depth, base, yaw, region) -> str:
    """What keeps a location out of a generated kitchen ("" when nothing does): reach, bearing, edges."""
    reach = distributions.reach
    points = corners(location)
    offset = points - np.asarray(base)
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    forward, left = c * offset[:, 0] + s * offset[:, 1], -s * offset[:, 0] + c * offset[:, 1]
    distance = np.hypot(forward, left)
    low, high = reach["location_reach"]
    if distance.min() < low - 1e-9 or distance.max() > high + 1e-9:
        return f"a corner is {distance.min():.3f}-{distance.max():.3f} m from the base (accepted {low}-{high} m)"
    if np.abs(np.degrees(np.arctan2(left, forward))).max() > reach["location_bearing_degrees"] + 1e-9:
        return f"a corner lies beyond {reach['location_bearing_degrees']} degrees of straight ahead"
    edge = reach["location_edge"]
    if (np.abs(points[:, 0]).max() > length / 2 - edge + 1e-9 or np.abs(points[:, 1]).max() > depth / 2 - edge + 1e-9):
        return f"it comes closer than {edge} m to the worktop's edge"
    if not (region["x"][0] <= location.centre[0] <= region["x"][1]
            and region["y"][0] <= location.centre[1] <= region["y"][1]):
        return "its centre lies outside the object region's box"
    return ""


def _arrangement_fits(locations: dict, distributions, length, depth, base, yaw, region) -> bool:
    if any(location_problem(location, distributions, length, depth, base, yaw, region)
           for location in locations.values()):
        return False
    gap = distributions.reach["location_gap"]
    placed = list(locations.values())
    for i, a in enumerate(placed):
        for b in placed[i + 1:]:
            if all(abs(a.centre[k] - b.centre[k]) < a.half_size[k] + b.half_size[k] + gap for k in (0, 1)):
                return False
    return True


def _camera(settings: dict, kitchen: Kitchen) -> dict:
    """A camera straight above the reachable object region, seeing all of it and ``margin`` around it."""
    xs = np.arange(kitchen.region_x[0], kitchen.region_x[1] + 1e-9, 0.01)
    ys = np.arange(kitchen.region_y[0], kitchen.region_y[1] + 1e-9, 0.01)
    grid = np.column_stack([axis.ravel() for axis in np.meshgrid(xs, ys)])
    inside = grid[kitchen.in_object_region(grid)]
    low, high = inside.min(axis=0) - settings["margin"], inside.max(axis=0) + settings["margin"]
    centre = [metres((low[0] + high[0]) / 2), metres((low[1] + high[1]) / 2)]
    aspect = settings["width"] / settings["height_pixels"]
    half_height = max((high[1] - low[1]) / 2, (high[0] - low[0]) / 2 / aspect)
    fov = math.ceil(math.degrees(2 * math.atan(half_height / settings["height"])) * 10) / 10
    return {"eye": [*centre, settings["height"]], "target": [*centre, 0.0], "up": [0.0, 1.0, 0.0],
            "fov_degrees": fov, "width": settings["width"], "height": settings["height_pixels"],
            "near": settings["near"], "far": settings["far"]}
