"""The generator's data file (``data/generator/kitchens.toml``), read and checked field by field: every problem
is one :class:`DataFileError` line naming the file, the field and what is accepted."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from bullet_world.datafiles import DATA_DIR, DataFileError, read_toml
from bullet_world.kitchen import INTEREST_POINTS
from bullet_world.room import FIXTURE_KINDS, read_materials
from learning.datafiles import check_keys, flag, integer, name, number, numbers, section, text, texts, value_range

DEFAULT_DISTRIBUTIONS = DATA_DIR / "generator" / "kitchens.toml"
TOP_FIELDS = ("name_prefix", "worktop", "reach", "camera", "lighting", "ambient_noise", "families", "runs",
              "materials", "palette", "locations", "households")
PALETTE_PARTS = ("worktop", "floor", "cabinets", "doors", "handles", "walls", "uppers", "fittings")
FAMILY_RANGES = {"length": (1.2, 3.0), "depth": (0.7, 1.6), "robot_offset": (-0.5, 0.5), "turn_degrees": (-30.0, 30.0),
                 "back_gap": (0.8, 3.0), "side_wall_gap": (0.05, 2.0)}   # each family's [low, high]: within these
ELSEWHERE = "elsewhere"


@dataclass(frozen=True)
class Family:
    """One layout family (galley, L-shape, island, U): its share of the kitchens, sizes and room."""

    name: str
    weight: float
    description: str
    ranges: dict[str, tuple[float, float]]      # FAMILY_RANGES
    back_run: bool
    wings: int
    side_walls: int
    tall_unit: float                             # chance of a fridge-freezer on the back run
    bearing_span: float
    bearing_jitter: float


@dataclass(frozen=True)
class Distributions:
    """Everything a kitchen is drawn from; ``sha256`` of the file's bytes goes into every kitchen drawn."""

    path: Path
    sha256: str
    name_prefix: str
    worktop: dict
    reach: dict
    camera: dict
    lighting: dict
    ambient_noise: dict
    families: tuple[Family, ...]
    runs: dict
    materials: dict[str, tuple[float, float, float]]
    palette: dict[str, tuple[str, ...]]
    locations: dict[str, dict]                   # name -> fixture, material choices, accent choices
    households: dict[str, dict]                  # task -> roles, others


def load_distributions(path: str | Path | None = None) -> Distributions:
    """Read and check the generator's data file (the shipped one when ``path`` is None)."""
    path = Path(path) if path is not None else DEFAULT_DISTRIBUTIONS
    table = read_toml(path, "kitchen generator")
    where = str(path)
    check_keys(table, where, required=TOP_FIELDS)
    materials = read_materials(section(table, "materials", where), f"{where} [materials]")
    return Distributions(
        path=path, sha256=hashlib.sha256(path.read_bytes()).hexdigest(),
        name_prefix=name(table, "name_prefix", where, what="kitchen name prefix"),
        worktop=_worktop(section(table, "worktop", where), f"{where} [worktop]"),
        reach=_reach(section(table, "reach", where), f"{where} [reach]"),
        camera=_camera(section(table, "camera", where), f"{where} [camera]"),
        lighting=_lighting(section(table, "lighting", where), f"{where} [lighting]"),
        ambient_noise=_ambient_noise(section(table, "ambient_noise", where), f"{where} [ambient_noise]"),
        families=_families(section(table, "families", where), f"{where} [families]"),
        runs=_runs(section(table, "runs", where), f"{where} [runs]"),
        materials=materials,
        palette=_palette(section(table, "palette", where), f"{where} [palette]", materials),
        locations=_locations(section(table, "locations", where), f"{where} [locations]", materials),
        households=_households(section(table, "households", where), f"{where} [households]"),
    )


def _worktop(table: dict, where: str) -> dict:
    check_keys(table, where, required=("thickness", "height", "base_inset", "pedestal"))
    return {"thickness": number(table, "thickness", where, above=0.0, high=0.2),
            "height": value_range(table, "height", where, low=0.5, high=1.2),
            "base_inset": number(table, "base_inset", where, low=0.0, high=0.1),
            "pedestal": numbers(table, "pedestal", where, length=2, above=0.0, high=0.5)}


def _reach(table: dict, where: str) -> dict:
    keys = ("min_reach", "max_reach", "max_bearing_degrees", "region_inset", "min_gap", "focus_ahead",
            "focus_spread", "location_reach", "location_bearing_degrees", "location_gap", "location_edge",
            "half_size", "tries")
    check_keys(table, where, required=keys)
    reach = {"min_reach": number(table, "min_reach", where, low=0.0, high=0.8)}
    reach["max_reach"] = number(table, "max_reach", where, above=reach["min_reach"], high=0.8)
    reach["location_reach"] = value_range(table, "location_reach", where, low=reach["min_reach"],
                                          high=reach["max_reach"])
    reach["max_bearing_degrees"] = number(table, "max_bearing_degrees", where, above=0.0, high=90.0)
    reach["location_bearing_degrees"] = number(table, "location_bearing_degrees", where, above=0.0,
                                               high=reach["max_bearing_degrees"])
    reach["region_inset"] = numbers(table, "region_inset", where, length=3, low=0.0, high=0.3)
    reach["focus_ahead"] = value_range(table, "focus_ahead", where, low=reach["min_reach"], high=reach["max_reach"])
    for key in ("min_gap", "location_gap", "location_edge"):
        reach[key] = number(table, key, where, low=0.0, high=0.2)
    reach["focus_spread"] = number(table, "focus_spread", where, above=0.0, high=1.0)
    sizes = table["half_size"]
    if not isinstance(sizes, list) or len(sizes) != 2:
        raise DataFileError(f"{where}: 'half_size' must be [[x low, x high], [y low, y high]], got {sizes!r}")
    reach["half_size"] = tuple(value_range({"half_size": item}, "half_size", f"{where} half_size {'xy'[axis]}",
                                           low=0.03, high=0.15) for axis, item in enumerate(sizes))
    reach["tries"] = integer(table, "tries", where, low=1, high=10000)
    return reach


def _camera(table: dict, where: str) -> dict:
    check_keys(table, where, required=("height", "width", "height_pixels", "margin", "near", "far"))
    camera = {"height": number(table, "height", where, above=0.5, high=10.0),
              "width": integer(table, "width", where, low=32, high=4096),
              "height_pixels": integer(table, "height_pixels", where, low=32, high=4096),
              "margin": number(table, "margin", where, low=0.0, high=1.0),
              "near": number(table, "near", where, above=0.0)}
    camera["far"] = number(table, "far", where, above=camera["height"])
    if camera["near"] >= camera["height"] - 0.3:
        raise DataFileError(f"{where}: 'near' must be below the camera's height minus 0.3 m "
                            f"(objects stand up to 0.3 m tall), got {camera['near']}")
    return camera


def _lighting(table: dict, where: str) -> dict:
    check_keys(table, where, required=("elevation_degrees", "direction_jitter", "ambient_low", "ambient_width",
                                       "diffuse_low", "diffuse_width", "colours", "colour_jitter", "colour"))
    colour = section(table, "colour", where)
    light = {key: numbers(colour, key, f"{where}.colour", length=3, low=0.0, high=1.0) for key in colour}
    chosen = texts(table, "colours", where, nonempty=True)
    for item in chosen:
        if item not in light:
            raise DataFileError(f"{where}: 'colours' names '{item}', which [lighting.colour] does not define; "
                                f"defined: {', '.join(light) or 'none'}")
    lighting = {"elevation_degrees": value_range(table, "elevation_degrees", where, low=5.0, high=90.0),
                "direction_jitter": value_range(table, "direction_jitter", where, low=0.0, high=2.0),
                "colours": {item: light[item] for item in chosen},
                "colour_jitter": value_range(table, "colour_jitter", where, low=0.0, high=0.5)}
    for part in ("ambient", "diffuse"):
        lighting[f"{part}_low"] = value_range(table, f"{part}_low", where, low=0.0, high=1.0)
        lighting[f"{part}_width"] = number(table, f"{part}_width", where, low=0.0,
                                           high=1.0 - lighting[f"{part}_low"][1])
    return lighting


def _ambient_noise(table: dict, where: str) -> dict:
    keys = ("level_low_db", "level_width_db", "events_per_minute", "event_low_db", "event_width_db")
    check_keys(table, where, required=keys)
    return {key: value_range(table, key, where, low=0.0, high=140.0) for key in keys}


def _families(table: dict, where: str) -> tuple[Family, ...]:
    if not table:
        raise DataFileError(f"{where}: name at least one layout family ([families.NAME])")
    families = []
    for family_name, entry in table.items():
        at = f"{where[:-1]}.{family_name}]"
        check_keys(entry, at, required=("weight", "description", *FAMILY_RANGES, "back_run", "wings", "side_walls",
                                        "tall_unit", "bearing_span_degrees", "bearing_jitter_degrees"))
        ranges = {key: value_range(entry, key, at, low=low, high=high) for key, (low, high) in FAMILY_RANGES.items()}
        families.append(Family(
            family_name, number(entry, "weight", at, above=0.0), text(entry, "description", at), ranges,
            flag(entry, "back_run", at), integer(entry, "wings", at, low=0, high=2),
            integer(entry, "side_walls", at, low=0, high=2), number(entry, "tall_unit", at, low=0.0, high=1.0),
            number(entry, "bearing_span_degrees", at, above=0.0, high=80.0),
            number(entry, "bearing_jitter_degrees", at, low=0.0, high=20.0)))
    return tuple(families)


def _runs(table: dict, where: str) -> dict:
    check_keys(table, where, required=("depth", "upper_height", "upper_depth", "upper_clearance", "sink",
                                       "tall_unit", "wall_height"))
    return {"depth": number(table, "depth", where, above=0.2, high=1.0),
            "upper_height": value_range(table, "upper_height", where, low=0.3, high=2.5),
            "upper_depth": number(table, "upper_depth", where, above=0.0, high=0.6),
            "upper_clearance": number(table, "upper_clearance", where, low=0.3, high=2.0),
            "sink": numbers(table, "sink", where, length=2, above=0.0, high=0.55),
            "tall_unit": numbers(table, "tall_unit", where, length=3, above=0.0, high=2.5),
            "wall_height": number(table, "wall_height", where, above=1.0, high=5.0)}


def _choices(table: dict, key: str, where: str, materials: dict) -> tuple[str, ...]:
    chosen = texts(table, key, where, nonempty=True)
    for item in chosen:
        if item not in materials:
            raise DataFileError(f"{where}: '{key}' names the unknown material '{item}'; [materials] has: "
                                f"{', '.join(sorted(materials))}")
    return tuple(chosen)


def _palette(table: dict, where: str, materials: dict) -> dict[str, tuple[str, ...]]:
    check_keys(table, where, required=PALETTE_PARTS)
    return {part: _choices(table, part, where, materials) for part in PALETTE_PARTS}


def _locations(table: dict, where: str, materials: dict) -> dict[str, dict]:
    check_keys(table, where, required=INTEREST_POINTS)
    locations = {}
    for location in INTEREST_POINTS:
        at = f"{where[:-1]}.{location}]"
        entry = section(table, location, where)
        check_keys(entry, at, required=("fixture", "material", "accent"))
        locations[location] = {"fixture": text(entry, "fixture", at, choices=FIXTURE_KINDS),
                               "material": _choices(entry, "material", at, materials),
                               "accent": _choices(entry, "accent", at, materials)}
    return locations


def _households(table: dict, where: str) -> dict[str, dict]:
    """``[households.TASK]``: roles and others, their kinds checked against the task's object file."""
    from bullet_world.catalogue import load_task
    from bullet_world.datafiles import available

    households = {}
    for task_name, entry in table.items():
        at = f"{where[:-1]}.{task_name}]"
        if task_name not in available("tasks"):
            raise DataFileError(f"{at}: no task '{task_name}'; tasks: {', '.join(available('tasks'))}")
        kinds = {kind.name for kind in load_task(task_name).kinds}
        places = (*INTEREST_POINTS, ELSEWHERE)
        check_keys(entry, at, required=("roles", "others"))
        roles, others = [], []
        for index, item in enumerate(_entries(entry, "roles", at)):
            here = f"{at} roles {index + 1}"
            check_keys(item, here, required=("role", "at", "kinds"))
            roles.append({"role": name(item, "role", here, what="role"), "at": text(item, "at", here, choices=places),
                          "kinds": _kinds(item, here, kinds)})
        for index, item in enumerate(_entries(entry, "others", at)):
            here = f"{at} others {index + 1}"
            check_keys(item, here, required=("at", "count", "kinds"))
            choices = _kinds(item, here, kinds)
            count = integer(item, "count", here, low=0, high=len(set(choices)))
            others.append({"at": text(item, "at", here, choices=places), "count": count, "kinds": choices})
        names = [role["role"] for role in roles]
        if len(set(names)) != len(names):
            raise DataFileError(f"{at}: each role may be named once, got {names}")
        households[task_name] = {"roles": roles, "others": others}
    return households


def _entries(table: dict, key: str, where: str) -> list[dict]:
    value = table[key]
    if not isinstance(value, list) or not all(isinstance(item, dict) for item in value):
        raise DataFileError(f"{where}: '{key}' must be a list of tables ({{ at = ..., kinds = [...] }}), got {value!r}")
    return value


def _kinds(item: dict, where: str, kinds: set[str]) -> tuple[str, ...]:
    chosen = texts(item, "kinds", where, nonempty=True)
    for kind in chosen:
        if kind not in kinds:
            raise DataFileError(f"{where}: 'kinds' names '{kind}', which the task's object file does not have; "
                                f"it has: {', '.join(sorted(kinds))}")
    return tuple(chosen)
