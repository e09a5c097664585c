"""Kitchens: counter, robot base, camera, lighting, ambient noise, semantic locations and the room around
them (``data/kitchens``; the room's format: :mod:`bullet_world.room`, docs/kitchen.md)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from bullet_world.datafiles import DataFileError, read_toml, resolve
from bullet_world.room import (
    FIXTURE_KINDS,
    FLUSH_M,
    Fixture,
    Piece,
    Room,
    base_cabinet_pieces,
    fixture_pieces,
    furniture_list,
    read_fixture,
    read_materials,
    read_room,
)
from learning.datafiles import check_keys, integer, number, numbers, text, value_range
from learning.datafiles import section as table_section

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
    room: Room | None = None             # None: a bare counter (no floor, cabinets or fixtures)
    fixtures: dict[str, Fixture] = field(default_factory=dict)   # location name -> what it is built as
    households: dict[str, tuple[dict, ...]] = field(default_factory=dict)  # task -> the dishes its recipes use
    generated: dict = field(default_factory=dict)   # a generated kitchen's seed, family and distributions
    path: str = ""                       # the file it was read from

    def lies_on_worktop(self, piece: Piece) -> bool:
        """A flat piece on the worktop (a fixture's top, a burner, a sink): no thicker than the worktop, its top
        at most FLUSH_M above it, and its footprint inside the worktop's."""
        half = np.asarray(self.counter_size[:2]) / 2
        inside = np.all(np.abs(np.asarray(piece.centre[:2]) - self.counter_centre) + np.asarray(piece.size[:2]) / 2
                        <= half + 1e-9)
        return bool(inside and 0.0 < piece.top <= FLUSH_M and piece.top - piece.size[2] >= -self.counter_size[2])

    def room_pieces(self) -> tuple[list[Piece], list[Piece]]:
        """(pieces under the worktop, pieces on or above it): the floor, base cabinets and fixture fronts
        (the overhead camera cannot see them past the worktop), then the fixtures' tops and the furniture."""
        if self.room is None:
            return [], []
        half = (self.counter_size[0] / 2, self.counter_size[1] / 2)
        thickness, floor_z = self.counter_size[2], -self.room.worktop_height
        under, above = [], []
        for name, fixture in self.fixtures.items():
            for piece in fixture_pieces(name, self.locations[name], fixture, self.counter_centre, half, thickness,
                                        floor_z):
                (above if piece.top > -thickness else under).append(piece)
        fronts = list(under)
        under = base_cabinet_pieces(self.room, self.counter_centre, half, thickness, fronts) + under
        return under, above + list(self.room.furniture)

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
    check_keys(table, where, required=("centre", "half_size"), optional=("fixture", "material", "accent"))
    half = numbers(table, "half_size", where, length=2, above=0.0)
    return Location(name, numbers(table, "centre", where, length=3), half)


def _camera(section: dict, where: str) -> dict:
    check_keys(section, where, required=("eye", "target", "up", "fov_degrees", "near", "far", "width", "height"))
    camera = {key: list(numbers(section, key, where, length=3)) for key in ("eye", "target", "up")}
    if camera["eye"] == camera["target"] or not any(camera["up"]):
        raise DataFileError(f"{where}: 'eye' and 'target' must differ and 'up' must not be [0, 0, 0]")
    camera["fov_degrees"] = number(section, "fov_degrees", where, above=0.0, below=180.0)
    camera["near"] = number(section, "near", where, above=0.0)
    camera["far"] = number(section, "far", where, above=camera["near"])
    for key in ("width", "height"):
        camera[key] = integer(section, key, where, low=32, high=4096)
    return camera


def _lighting(section: dict, where: str) -> dict:
    check_keys(section, where, required=("direction", "direction_jitter", "ambient", "diffuse"),
               optional=("colour", "colour_jitter"))
    direction = numbers(section, "direction", where, length=3)
    if not any(direction):
        raise DataFileError(f"{where}: 'direction' must not be [0, 0, 0]")
    return {
        "direction": list(direction),
        "direction_jitter": number(section, "direction_jitter", where, low=0.0),
        "ambient": value_range(section, "ambient", where, low=0.0, high=1.0),
        "diffuse": value_range(section, "diffuse", where, low=0.0, high=1.0),
        "colour": numbers(section, "colour", where, (1.0, 1.0, 1.0), length=3, low=0.0, high=1.0),
        "colour_jitter": number(section, "colour_jitter", where, 0.0, low=0.0),
    }


def _ambient_noise(section: dict, where: str) -> dict:
    check_keys(section, where, optional=("level_db", "events_per_minute", "event_db"))
    return {
        "level_db": value_range(section, "level_db", where, (35.0, 45.0), low=0.0),
        "events_per_minute": number(section, "events_per_minute", where, 1.0, low=0.0),
        "event_db": value_range(section, "event_db", where, (55.0, 70.0), low=0.0),
    }


def _object_region(region: dict, where: str) -> dict:
    check_keys(region, where, required=("x", "y", "min_gap"),
               optional=("min_reach", "max_reach", "max_bearing_degrees", "focus", "focus_spread"))
    min_reach = number(region, "min_reach", where, 0.0, low=0.0)
    return {
        "region_x": value_range(region, "x", where), "region_y": value_range(region, "y", where),
        "min_gap": number(region, "min_gap", where, low=0.0), "min_reach": min_reach,
        "max_reach": number(region, "max_reach", where, float("inf"), above=min_reach),
        "max_bearing": number(region, "max_bearing_degrees", where, 180.0, above=0.0, high=180.0),
        "focus": numbers(region, "focus", where, None, length=2),
        "focus_spread": number(region, "focus_spread", where, 0.25, above=0.0),
    }


def load_kitchen(name_or_path) -> Kitchen:
    """Load ``data/kitchens/NAME.toml`` (or a path) and check that every location is within reach."""
    path = resolve("kitchens", name_or_path)
    table = read_toml(path, "kitchen")
    where = str(path)
    check_keys(table, where, required=("name", "counter", "robot", "object_region", "camera", "lighting", "locations"),
               optional=("description", "ambient_noise", "materials", "room", "furniture", "households",
                         "generated"))
    section = {key: table_section(table, key, where) for key in
               ("counter", "robot", "object_region", "camera", "lighting", "locations")}
    counter, robot = section["counter"], section["robot"]
    check_keys(counter, f"{where} [counter]", required=("size", "centre", "colour"))
    check_keys(robot, f"{where} [robot]", required=("base", "yaw_degrees"))
    kitchen = Kitchen(
        name=text(table, "name", where),
        description=text(table, "description", where, "", nonempty=False),
        counter_size=numbers(counter, "size", f"{where} [counter]", length=3, above=0.0),
        counter_centre=numbers(counter, "centre", f"{where} [counter]", length=2),
        counter_colour=numbers(counter, "colour", f"{where} [counter]", length=3, low=0.0, high=1.0),
        robot_base=numbers(robot, "base", f"{where} [robot]", length=3),
        robot_yaw=float(np.radians(number(robot, "yaw_degrees", f"{where} [robot]"))),
        **_object_region(section["object_region"], f"{where} [object_region]"),
        camera=_camera(section["camera"], f"{where} [camera]"),
        lighting=_lighting(section["lighting"], f"{where} [lighting]"),
        ambient_noise=_ambient_noise(table_section(table, "ambient_noise", where, {}), f"{where} [ambient_noise]"),
        locations={name: _location(name, entry, f"{where} [locations.{name}]")
                   for name, entry in section["locations"].items()},
        generated=_generated(table_section(table, "generated", where, {}), f"{where} [generated]"),
        path=where,
    )
    missing = [name for name in INTEREST_POINTS if name not in kitchen.locations]
    if missing:
        raise DataFileError(f"{where} [locations]: every kitchen needs the interest points "
                            f"{', '.join(INTEREST_POINTS)}; missing {', '.join(missing)}")
    kitchen = _furnish(kitchen, table, where)
    kitchen = replace(kitchen, households=_households(table_section(table, "households", where, {}), where,
                                                      kitchen.locations))
    base = np.asarray(kitchen.robot_base[:2])
    for location in kitchen.locations.values():
        distance = float(np.linalg.norm(np.asarray(location.centre[:2]) - base))
        if distance > ARM_REACH_M:
            raise DataFileError(f"{where} [locations.{location.name}]: centre is {distance:.2f} m from the robot "
                                f"base; locations must be within {ARM_REACH_M} m so the arm can reach them")
    return kitchen


def _furnish(kitchen: Kitchen, table: dict, where: str) -> Kitchen:
    """Add the room, furniture and fixtures, and refuse furniture that stands above the worktop where objects
    may be placed (the arm reaches there and the camera must see every object whole)."""
    if "room" not in table:
        for key in ("materials", "furniture"):
            if key in table:
                raise DataFileError(f"{where}: '{key}' needs a [room] table (worktop_height, floor, cabinets, doors, "
                                    f"handles)")
        for name, entry in table["locations"].items():
            if "fixture" in entry:
                raise DataFileError(f"{where} [locations.{name}]: a 'fixture' needs a [room] table")
        return kitchen
    materials = read_materials(table_section(table, "materials", where, {}), f"{where} [materials]")
    room = read_room(table_section(table, "room", where), f"{where} [room]", materials, furniture_list(table, where),
                     where)
    fixtures = {}
    for name, entry in table["locations"].items():
        fixture = read_fixture(entry, f"{where} [locations.{name}]", materials)
        if fixture is None:
            raise DataFileError(f"{where} [locations.{name}]: in a kitchen with a [room] every location is built "
                                f"as a fixture; add 'fixture' (one of {', '.join(FIXTURE_KINDS)}) and its "
                                f"'material' and 'accent'")
        fixtures[name] = fixture
    for index, piece in enumerate(room.furniture):
        if piece.top > FLUSH_M and kitchen.in_object_region(piece.footprint_points()).any():
            raise DataFileError(f"{where} [[furniture]] {index + 1} ('{piece.name}'): it rises "
                                f"{piece.top:.2f} m above the worktop where objects may be placed "
                                f"([object_region]); only pieces flush with the worktop (top <= {FLUSH_M} m) may "
                                f"stand there")
    return replace(kitchen, room=room, fixtures=fixtures)


def _generated(table: dict, where: str) -> dict:
    """``[generated]``: where a generated kitchen came from (``teachbot world generate``)."""
    if not table:
        return {}
    check_keys(table, where, required=("seed", "family", "distributions", "sha256"))
    sha = text(table, "sha256", where)
    if len(sha) != 64 or any(c not in "0123456789abcdef" for c in sha):
        raise DataFileError(f"{where}: 'sha256' must be 64 lowercase hex digits, got {sha!r}")
    return {"seed": integer(table, "seed", where, low=0), "family": text(table, "family", where),
            "distributions": text(table, "distributions", where), "sha256": sha}


def _households(table: dict, where: str, locations: dict) -> dict[str, tuple[dict, ...]]:
    """``[households.TASK]``: ``objects`` = [{ kind, role (optional), at }], each "at" one of the kitchen's
    locations or "elsewhere"; the kinds are checked against the task when a recipe uses them."""
    from bullet_world.datafiles import available

    households = {}
    places = (*locations, "elsewhere")
    for task, entry in table.items():
        at = f"{where} [households.{task}]"
        if task not in available("tasks"):
            raise DataFileError(f"{at}: no task '{task}'; tasks: {', '.join(available('tasks'))}")
        check_keys(entry, at, required=("objects",))
        objects = entry["objects"]
        if not isinstance(objects, list) or not objects or not all(isinstance(item, dict) for item in objects):
            raise DataFileError(f"{at}: 'objects' must be a non-empty list of {{ kind, role, at }} tables, "
                                f"got {objects!r}")
        for index, item in enumerate(objects, 1):
            here = f"{at} object {index}"
            check_keys(item, here, required=("kind", "at"), optional=("role",))
            text(item, "kind", here)
            text(item, "role", here, "")
            text(item, "at", here, choices=places)
        households[task] = tuple(objects)
    return households
