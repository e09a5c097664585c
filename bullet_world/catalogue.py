"""Kitchens, tasks and object kinds, loaded from the TOML files in ``data/``.

Every loader validates what it reads and raises :class:`DataFileError` with a
one-line message naming the file, the field, and what is accepted.
"""

from __future__ import annotations

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DATA_DIR = Path(__file__).parent / "data"
SHAPES = {"box": ("length", "width", "height"), "cylinder": ("radius", "height"), "sphere": ("radius",)}


class DataFileError(ValueError):
    """A kitchen, task or object file is missing, malformed or inconsistent."""


def _read_toml(path: Path) -> dict:
    try:
        with open(path, "rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        raise DataFileError(f"{path}: no such file") from None
    except tomllib.TOMLDecodeError as error:
        raise DataFileError(f"{path}: not valid TOML ({error})") from None


def _field(table: dict, key: str, where: str, kind: type | tuple = (int, float), length: int | None = None):
    """Return ``table[key]`` after checking its type (and list length)."""
    if key not in table:
        raise DataFileError(f"{where}: missing field '{key}'")
    value = table[key]
    if length is not None:
        if not isinstance(value, list) or len(value) != length or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
        ):
            raise DataFileError(f"{where}: '{key}' must be a list of {length} numbers, got {value!r}")
        return [float(v) for v in value]
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise DataFileError(f"{where}: '{key}' has the wrong type ({type(value).__name__}), got {value!r}")
    return value


def _range(table: dict, key: str, where: str) -> tuple[float, float]:
    low, high = _field(table, key, where, length=2)
    if not 0 <= low <= high:
        raise DataFileError(f"{where}: '{key}' must be [low, high] with 0 <= low <= high, got {[low, high]}")
    return low, high


def _available(folder: str) -> list[str]:
    return sorted(p.stem for p in (DATA_DIR / folder).glob("*.toml"))


def _resolve(folder: str, name_or_path: str | Path) -> Path:
    path = Path(name_or_path)
    if path.suffix == ".toml":
        return path
    candidate = DATA_DIR / folder / f"{name_or_path}.toml"
    if not candidate.exists():
        raise DataFileError(f"unknown {folder[:-1]} '{name_or_path}'; available: {', '.join(_available(folder))}")
    return candidate


@dataclass(frozen=True)
class ObjectKind:
    """One kind of object (apple, soda can) and the distributions it is drawn from."""

    name: str
    concept: str
    shape: str
    dimensions: dict[str, tuple[float, float]]
    colours: tuple[tuple[float, float, float], ...]
    colour_jitter: float
    mass: tuple[float, float]

    def sample(self, rng: np.random.Generator) -> dict:
        """Draw one object's size, colour and mass."""
        dims = {key: float(rng.uniform(*bounds)) for key, bounds in self.dimensions.items()}
        base = np.asarray(self.colours[rng.integers(len(self.colours))])
        colour = np.clip(base + rng.normal(0.0, self.colour_jitter, 3), 0.0, 1.0)
        return {"dimensions": dims, "colour": colour, "mass": float(rng.uniform(*self.mass))}


def load_object_kinds(name_or_path: str | Path) -> list[ObjectKind]:
    """Load a catalogue of object kinds from ``data/objects/NAME.toml`` (or a path)."""
    path = _resolve("objects", name_or_path)
    kinds = _read_toml(path).get("kind")
    if not isinstance(kinds, list) or not kinds:
        raise DataFileError(f"{path}: needs at least one [[kind]] table")
    result = []
    for index, table in enumerate(kinds):
        where = f"{path}: kind {index + 1}"
        shape = _field(table, "shape", where, str)
        if shape not in SHAPES:
            raise DataFileError(f"{where}: shape '{shape}' is not one of {', '.join(SHAPES)}")
        colours = _field(table, "colours", where, list)
        if not colours:
            raise DataFileError(f"{where}: 'colours' must list at least one [r, g, b]")
        for colour in colours:
            _field({"colour": colour}, "colour", where, length=3)
        result.append(
            ObjectKind(
                name=_field(table, "name", where, str),
                concept=_field(table, "concept", where, str),
                shape=shape,
                dimensions={key: _range(table, key, where) for key in SHAPES[shape]},
                colours=tuple(tuple(float(c) for c in colour) for colour in colours),
                colour_jitter=float(_field(table, "colour_jitter", where)),
                mass=_range(table, "mass", where),
            )
        )
    return result


@dataclass(frozen=True)
class Task:
    """The concepts to ground and how scenes are filled."""

    name: str
    description: str
    concepts: tuple[str, ...]
    kinds: tuple[ObjectKind, ...]
    objects_per_scene: int
    test_scenes: int


def load_task(name_or_path: str | Path) -> Task:
    """Load ``data/tasks/NAME.toml`` and its object catalogue."""
    path = _resolve("tasks", name_or_path)
    table = _read_toml(path)
    where = str(path)
    concepts = tuple(_field(table, "concepts", where, list))
    kinds = tuple(load_object_kinds(_field(table, "objects", where, str)))
    missing = sorted({k.concept for k in kinds} - set(concepts))
    if missing:
        raise DataFileError(f"{where}: object kinds use concepts not in 'concepts': {missing}")
    uncovered = sorted(set(concepts) - {k.concept for k in kinds})
    if uncovered:
        raise DataFileError(f"{where}: no object kind for concepts {uncovered}")
    count = _field(table, "objects_per_scene", where, int)
    if count < len(concepts):
        raise DataFileError(f"{where}: 'objects_per_scene' must be at least the number of concepts ({len(concepts)})")
    return Task(
        name=_field(table, "name", where, str),
        description=table.get("description", ""),
        concepts=concepts,
        kinds=kinds,
        objects_per_scene=count,
        test_scenes=_field(table, "test_scenes", where, int),
    )


@dataclass(frozen=True)
class Kitchen:
    """Counter geometry, robot base, camera, lighting and interest points."""

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

    @property
    def interest_points(self) -> dict[str, tuple[float, float, float]]:
        """The centre of every semantic location."""
        return {name: location.centre for name, location in self.locations.items()}


@dataclass(frozen=True)
class Location:
    """A semantic location ("stove"): a centre on the counter and the half size of its region."""

    name: str
    centre: tuple[float, float, float]
    half_size: tuple[float, float]

    def contains(self, xy) -> bool:
        return all(abs(float(xy[i]) - self.centre[i]) <= self.half_size[i] for i in range(2))


def _location(name: str, table, where: str) -> Location:
    if not isinstance(table, dict):
        raise DataFileError(f"{where}: must be a table with 'centre' = [x, y, z] and 'half_size' = [hx, hy]")
    half = _field(table, "half_size", where, length=2)
    if min(half) <= 0:
        raise DataFileError(f"{where}: 'half_size' must be positive, got {half}")
    return Location(name, tuple(_field(table, "centre", where, length=3)), tuple(half))


def load_kitchen(name_or_path: str | Path) -> Kitchen:
    """Load ``data/kitchens/NAME.toml``."""
    path = _resolve("kitchens", name_or_path)
    table = _read_toml(path)
    where = str(path)
    section = {key: _field(table, key, where, dict) for key in
               ("counter", "robot", "object_region", "camera", "lighting", "locations")}
    cam = section["camera"]
    camera = {key: _field(cam, key, f"{where} [camera]", length=3) for key in ("eye", "target", "up")}
    for key in ("fov_degrees", "near", "far"):
        camera[key] = float(_field(cam, key, f"{where} [camera]"))
    for key in ("width", "height"):
        camera[key] = int(_field(cam, key, f"{where} [camera]", int))
    light = section["lighting"]
    lighting = {
        "direction": _field(light, "direction", f"{where} [lighting]", length=3),
        "direction_jitter": float(_field(light, "direction_jitter", f"{where} [lighting]")),
        "ambient": _range(light, "ambient", f"{where} [lighting]"),
        "diffuse": _range(light, "diffuse", f"{where} [lighting]"),
    }
    region = section["object_region"]
    return Kitchen(
        name=_field(table, "name", where, str),
        counter_size=tuple(_field(section["counter"], "size", f"{where} [counter]", length=3)),
        counter_centre=tuple(_field(section["counter"], "centre", f"{where} [counter]", length=2)),
        counter_colour=tuple(_field(section["counter"], "colour", f"{where} [counter]", length=3)),
        robot_base=tuple(_field(section["robot"], "base", f"{where} [robot]", length=3)),
        robot_yaw=float(np.radians(_field(section["robot"], "yaw_degrees", f"{where} [robot]"))),
        region_x=tuple(_field(region, "x", f"{where} [object_region]", length=2)),
        region_y=tuple(_field(region, "y", f"{where} [object_region]", length=2)),
        min_gap=float(_field(region, "min_gap", f"{where} [object_region]")),
        camera=camera,
        lighting=lighting,
        locations={name: _location(name, table, f"{where} [locations.{name}]")
                   for name, table in section["locations"].items()},
    )
