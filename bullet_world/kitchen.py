"""Kitchens: counter, robot base, camera, lighting, ambient noise and semantic locations (``data/kitchens``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bullet_world.datafiles import DataFileError, number_range, optional, read_toml, resolve
from bullet_world.datafiles import field as table_field

# The interest points every kitchen places (thesis Table 5.1: "location relative to five interest points").
INTEREST_POINTS = ("stove", "fridge", "cupboard", "pantry", "counter")
ARM_REACH_M = 0.8  # every semantic location must lie within this distance of the robot base


@dataclass(frozen=True)
class Location:
    """A semantic location ("stove"): a centre on the counter and the half size of its region."""

    name: str
    centre: tuple[float, float, float]
    half_size: tuple[float, float]

    def contains(self, xy) -> bool:
        return all(abs(float(xy[i]) - self.centre[i]) <= self.half_size[i] for i in range(2))


@dataclass(frozen=True)
class Kitchen:
    """Counter geometry, robot base, camera, lighting, noise and interest points."""

    name: str
    counter_size: tuple[float, float, float]
    counter_centre: tuple[float, float]
    counter_colour: tuple[float, float, float]
    robot_base: tuple[float, float, float]
    robot_yaw: float
    region_x: tuple[float, float]
    region_y: tuple[float, float]
    min_gap: float
    camera: dict
    lighting: dict
    locations: dict[str, Location]
    description: str = ""
    min_reach: float = 0.0
    max_reach: float = float("inf")
    max_bearing: float = 180.0           # degrees either side of straight ahead where objects may stand
    focus: tuple[float, float] | None = None  # where objects gather (the work area); None: anywhere alike
    focus_spread: float = 0.25           # metres: how tightly objects gather around the focus
    ambient_noise: dict = field(default_factory=dict)

    @property
    def interest_points(self) -> dict[str, tuple[float, float, float]]:
        """The centre of every semantic location."""
        return {name: location.centre for name, location in self.locations.items()}

    def robot_frame(self, xy: np.ndarray) -> np.ndarray:
        """Points (n, 2) in the robot base frame: forward (along the arm's x axis) and left."""
        offset = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2] - np.asarray(self.robot_base[:2])
        c, s = np.cos(self.robot_yaw), np.sin(self.robot_yaw)
        return np.column_stack([c * offset[:, 0] + s * offset[:, 1], -s * offset[:, 0] + c * offset[:, 1]])

    def in_object_region(self, xy: np.ndarray) -> np.ndarray:
        """Which points (n, 2) may hold an object centre: inside the region box, within reach, and
        within ``max_bearing`` of straight ahead of the robot."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        inside = ((xy[:, 0] >= self.region_x[0]) & (xy[:, 0] <= self.region_x[1])
                  & (xy[:, 1] >= self.region_y[0]) & (xy[:, 1] <= self.region_y[1]))
        local = self.robot_frame(xy)
        distance = np.hypot(local[:, 0], local[:, 1])
        inside &= (distance >= self.min_reach) & (distance <= self.max_reach)
        if self.max_bearing < 180.0:
            inside &= np.abs(np.degrees(np.arctan2(local[:, 1], local[:, 0]))) <= self.max_bearing
        return inside

    def counter_edge_distance(self, xy: np.ndarray) -> np.ndarray:
        """Distance (n,) from each point to the nearest edge of the counter top."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        half = np.asarray(self.counter_size[:2]) / 2
        offset = np.abs(xy[:, :2] - np.asarray(self.counter_centre))
        return np.min(half - offset, axis=1)


def _location(name: str, table, where: str) -> Location:
    if not isinstance(table, dict):
        raise DataFileError(f"{where}: must be a table with 'centre' = [x, y, z] and 'half_size' = [hx, hy]")
    half = table_field(table, "half_size", where, length=2)
    if min(half) <= 0:
        raise DataFileError(f"{where}: 'half_size' must be positive, got {half}")
    return Location(name, tuple(table_field(table, "centre", where, length=3)), tuple(half))


def _camera(section: dict, where: str) -> dict:
    camera = {key: table_field(section, key, where, length=3) for key in ("eye", "target", "up")}
    for key in ("fov_degrees", "near", "far"):
        camera[key] = float(table_field(section, key, where))
    for key in ("width", "height"):
        camera[key] = int(table_field(section, key, where, int))
        if not 32 <= camera[key] <= 4096:
            raise DataFileError(f"{where}: '{key}' must be between 32 and 4096 pixels, got {camera[key]}")
    return camera


def _lighting(section: dict, where: str) -> dict:
    return {
        "direction": table_field(section, "direction", where, length=3),
        "direction_jitter": float(table_field(section, "direction_jitter", where)),
        "ambient": number_range(section, "ambient", where),
        "diffuse": number_range(section, "diffuse", where),
        "colour": tuple(optional(section, "colour", where, [1.0, 1.0, 1.0], length=3)),
        "colour_jitter": float(optional(section, "colour_jitter", where, 0.0)),
    }


def _ambient_noise(section: dict, where: str) -> dict:
    return {
        "level_db": number_range(section, "level_db", where) if "level_db" in section else (35.0, 45.0),
        "events_per_minute": float(optional(section, "events_per_minute", where, 1.0)),
        "event_db": number_range(section, "event_db", where) if "event_db" in section else (55.0, 70.0),
    }


def load_kitchen(name_or_path) -> Kitchen:
    """Load ``data/kitchens/NAME.toml`` (or a path) and check that every location is within reach."""
    path = resolve("kitchens", name_or_path)
    table = read_toml(path)
    where = str(path)
    section = {key: table_field(table, key, where, dict) for key in
               ("counter", "robot", "object_region", "camera", "lighting", "locations")}
    region = section["object_region"]
    region_where = f"{where} [object_region]"
    focus = optional(region, "focus", region_where, None, length=2)
    kitchen = Kitchen(
        name=table_field(table, "name", where, str),
        description=table.get("description", ""),
        counter_size=tuple(table_field(section["counter"], "size", f"{where} [counter]", length=3)),
        counter_centre=tuple(table_field(section["counter"], "centre", f"{where} [counter]", length=2)),
        counter_colour=tuple(table_field(section["counter"], "colour", f"{where} [counter]", length=3)),
        robot_base=tuple(table_field(section["robot"], "base", f"{where} [robot]", length=3)),
        robot_yaw=float(np.radians(table_field(section["robot"], "yaw_degrees", f"{where} [robot]"))),
        region_x=tuple(table_field(region, "x", region_where, length=2)),
        region_y=tuple(table_field(region, "y", region_where, length=2)),
        min_gap=float(table_field(region, "min_gap", region_where)),
        min_reach=float(optional(region, "min_reach", region_where, 0.0)),
        max_reach=float(optional(region, "max_reach", region_where, float("inf"))),
        max_bearing=float(optional(region, "max_bearing_degrees", region_where, 180.0)),
        focus=tuple(focus) if focus else None,
        focus_spread=float(optional(region, "focus_spread", region_where, 0.25)),
        camera=_camera(section["camera"], f"{where} [camera]"),
        lighting=_lighting(section["lighting"], f"{where} [lighting]"),
        ambient_noise=_ambient_noise(table.get("ambient_noise", {}), f"{where} [ambient_noise]"),
        locations={name: _location(name, entry, f"{where} [locations.{name}]")
                   for name, entry in section["locations"].items()},
    )
    missing = [name for name in INTEREST_POINTS if name not in kitchen.locations]
    if missing:
        raise DataFileError(f"{where} [locations]: every kitchen needs the interest points "
                            f"{', '.join(INTEREST_POINTS)}; missing {', '.join(missing)}")
    base = np.asarray(kitchen.robot_base[:2])
    for location in kitchen.locations.values():
        distance = float(np.linalg.norm(np.asarray(location.centre[:2]) - base))
        if distance > ARM_REACH_M:
            raise DataFileError(f"{where} [locations.{location.name}]: centre is {distance:.2f} m from the robot "
                                f"base; locations must be within {ARM_REACH_M} m so the arm can reach them")
    return kitchen
