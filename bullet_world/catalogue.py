"""Object kinds and tasks, loaded from the TOML files in ``data/objects`` and ``data/tasks``.

An object kind belongs to one concept and draws shape, size, colour, mass and
texture from per-kind distributions. A kind may have states in order (pasta:
boxed -> in a pot -> in a bowl); a kind without states has one. Kitchens live
in :mod:`bullet_world.kitchen` and are re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bullet_world.datafiles import DATA_DIR, DataFileError, colour_list, read_toml, resolve
from bullet_world.kitchen import INTEREST_POINTS, Kitchen, Location, load_kitchen
from learning.datafiles import check_keys, flag, integer, number, numbers, section, tables, text, texts, value_range
from learning.limits import maximum

__all__ = ["DATA_DIR", "SHAPES", "DataFileError", "Kitchen", "KindState", "Location", "ObjectKind", "Task",
           "load_kitchen", "load_object_kinds", "load_task"]

# Shape family -> the size fields it draws (metres). See bullet_world/meshes.py for the geometry.
SHAPES = {
    "box": ("length", "width", "height"),
    "cylinder": ("radius", "height"),
    "sphere": ("radius",),
    "lathe": ("radius", "height"),       # a surface of revolution given by 'profile'
    "bag": ("length", "width", "height"),  # a sealed, puffed pouch
    "slices": ("radius", "height"),      # 'count' half-disc slices laid flat in a row
}
STATE_FIELDS = ("shape", "length", "width", "height", "radius", "colours", "colour_jitter", "mass", "texture",
                "inner_colour", "location", "profile", "open", "fill", "count")
KIND_FIELDS = ("name", "concept", "kitchens", "state")
TASK_FIELDS = ("name", "description", "concepts", "objects", "objects_per_scene", "max_objects_per_scene",
               "test_scenes", "placement", "state_change_probability", "relevant_features", "datasets",
               "recipe_scenes")
TEXTURES = ("plain", "speckle", "print", "crinkle", "stripes", "label", "window", "metal", "ceramic", "flesh",
            "wrapper")


@dataclass(frozen=True)
class KindState:
    """How objects of a kind look in one state: shape, size, colour, mass and texture distributions."""

    name: str
    shape: str
    dimensions: dict[str, tuple[float, float]]
    colours: tuple[tuple[float, float, float], ...]
    colour_jitter: float
    mass: tuple[float, float]
    texture: str = "plain"
    inner_colour: tuple[float, float, float] = (0.9, 0.85, 0.7)
    location: str | None = None          # semantic location where the task places it
    profile: tuple[tuple[float, float], ...] = ()  # lathe: (radius fraction, height fraction) from bottom up
    open_top: bool = False               # lathe: a vessel (pot, bowl) rather than a solid
    fill: float = 0.0                    # vessel: height of the contents as a fraction of the height
    count: int = 3                       # slices


@dataclass(frozen=True)
class ObjectKind:
    """One kind of object (apple, soda can) and the distributions it is drawn from.

    ``shape``, ``dimensions``, ``colours``, ``colour_jitter`` and ``mass`` are those of the first state.
    """

    name: str
    concept: str
    shape: str
    dimensions: dict[str, tuple[float, float]]
    colours: tuple[tuple[float, float, float], ...]
    colour_jitter: float
    mass: tuple[float, float]
    states: tuple[KindState, ...] = ()
    kitchens: tuple[str, ...] = ()       # empty: found in every kitchen

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(state.name for state in self.states)

    def state(self, index: int) -> KindState:
        return self.states[min(max(int(index), 0), len(self.states) - 1)]

    def sample(self, rng: np.random.Generator, state: int = 0) -> dict:
        """Draw one object's size, colour, mass (and which base colour it tints) in ``state``."""
        look = self.state(state)
        dims = {key: float(rng.uniform(*bounds)) for key, bounds in look.dimensions.items()}
        index = int(rng.integers(len(look.colours)))
        base = np.asarray(look.colours[index])
        tint = np.clip(1.0 - np.abs(rng.normal(0.0, look.colour_jitter, 3)) * 1.5, 0.0, 1.0)
        return {"dimensions": dims, "colour": base * tint, "colour_index": index,
                "mass": float(rng.uniform(*look.mass)), "state": min(max(int(state), 0), len(self.states) - 1)}


def _profile(table: dict, where: str) -> tuple[tuple[float, float], ...]:
    points = table.get("profile")
    if not isinstance(points, list) or len(points) < 2:
        raise DataFileError(f"{where}: 'profile' needs at least two [radius, height] points, got {points!r}")
    profile = tuple(numbers({"profile": p}, "profile", f"{where} profile point {i + 1}", length=2, low=0.0, high=1.0)
                    for i, p in enumerate(points))
    heights = [p[1] for p in profile]
    if heights != sorted(heights) or heights[0] != 0.0 or heights[-1] != 1.0:
        raise DataFileError(f"{where}: 'profile' points must rise from height 0 to 1 with radii in 0..1")
    return profile


def _state(table: dict, name: str, where: str, defaults: dict) -> KindState:
    """One state from ``table``; fields it leaves out come from ``defaults`` (the kind's own fields)."""
    merged = {**defaults, **table}
    shape = text(merged, "shape", where, choices=SHAPES)
    return KindState(
        name=name, shape=shape,
        dimensions={key: _size(merged, key, where) for key in SHAPES[shape]},
        colours=colour_list(merged, "colours", where), colour_jitter=number(merged, "colour_jitter", where, low=0.0),
        mass=value_range(merged, "mass", where, low=0.0), texture=text(merged, "texture", where, "plain",
                                                                        choices=TEXTURES),
        inner_colour=numbers(merged, "inner_colour", where, (0.9, 0.85, 0.7), length=3, low=0.0, high=1.0),
        location=text(merged, "location", where, None, choices=INTEREST_POINTS),
        profile=_profile(merged, where) if shape == "lathe" else (), open_top=flag(merged, "open", where, False),
        fill=number(merged, "fill", where, 0.0, low=0.0, below=1.0), count=integer(merged, "count", where, 3, 1, 8),
    )


def _size(table: dict, key: str, where: str) -> tuple[float, float]:
    """A size range in metres: [low, high] with 0 < low <= high."""
    numbers(table, key, where, length=2, above=0.0)
    return value_range(table, key, where)


def load_object_kinds(name_or_path: str | Path) -> list[ObjectKind]:
    """Load a catalogue of object kinds from ``data/objects/NAME.toml`` (or a path)."""
    path = resolve("objects", name_or_path)
    table = read_toml(path, "objects")
    check_keys(table, str(path), required=("kind",))
    kinds = tables(table, "kind", str(path), nonempty=True)
    result = []
    for index, table in enumerate(kinds):
        where = f"{path}: kind {index + 1}"
        check_keys(table, where, required=("name", "concept"), optional=KIND_FIELDS[2:] + STATE_FIELDS)
        name = text(table, "name", where)
        defaults = {key: value for key, value in table.items() if key not in KIND_FIELDS}
        state_tables = tables(table, "state", where, [])
        states = []
        for i, entry in enumerate(state_tables):
            here = f"{where} ({name}) state {i + 1}"
            check_keys(entry, here, required=("name",), optional=STATE_FIELDS)
            states.append(_state(entry, text(entry, "name", here), here, defaults))
        if not states:
            states = [_state({}, "as-is", f"{where} ({name})", defaults)]
        first = states[0]
        result.append(ObjectKind(
            name=name, concept=text(table, "concept", where), shape=first.shape,
            dimensions=first.dimensions, colours=first.colours, colour_jitter=first.colour_jitter, mass=first.mass,
            states=tuple(states), kitchens=texts(table, "kitchens", where, ()),
        ))
    names = [kind.name for kind in result]
    if len(set(names)) != len(names):
        raise DataFileError(f"{path}: kind names must be unique")
    return result


@dataclass(frozen=True)
class DatasetPlan:
    """Thesis §6.5.1: disjoint training pools and one held-out test pool per task."""

    pools: int = 5
    pool_size: int = 400
    test_size: int = 200
    objects_per_scene: int = 12


@dataclass(frozen=True)
class Task:
    """The concepts to ground and how scenes are filled."""

    name: str
    description: str
    concepts: tuple[str, ...]
    kinds: tuple[ObjectKind, ...]
    objects_per_scene: int
    test_scenes: int
    max_objects_per_scene: int = 0
    place_at_locations: bool = False     # put objects whose state names a location there
    state_change_probability: float = 0.0
    relevant_patterns: tuple[str, ...] = ()
    datasets: DatasetPlan = field(default_factory=DatasetPlan)
    path: str = ""                       # the task file
    objects_path: str = ""               # its object catalogue file

    @property
    def relevant_features(self) -> tuple[str, ...]:
        """Names of the features that matter for this task's concepts (ground truth for HFS)."""
        from bullet_world.features import resolve_feature_patterns

        return resolve_feature_patterns(self.relevant_patterns, self.path or self.name)

    @property
    def has_states(self) -> bool:
        return any(len(kind.states) > 1 for kind in self.kinds)

    def kinds_in(self, kitchen: str) -> tuple[ObjectKind, ...]:
        """The kinds found in ``kitchen``; every concept must keep at least one."""
        kinds = tuple(k for k in self.kinds if not k.kitchens or kitchen in k.kitchens)
        uncovered = sorted(set(self.concepts) - {k.concept for k in kinds})
        if uncovered:
            raise DataFileError(f"task '{self.name}' has no object kind for {uncovered} in kitchen '{kitchen}'")
        return kinds


def _dataset_plan(table: dict, where: str, default_objects: int) -> DatasetPlan:
    check_keys(table, where, optional=("pools", "pool_size", "test_size", "objects_per_scene"))
    return DatasetPlan(
        pools=integer(table, "pools", where, 5, low=1, high=maximum("datasets")),
        pool_size=integer(table, "pool_size", where, 400, low=1),
        test_size=integer(table, "test_size", where, 200, low=1),
        objects_per_scene=integer(table, "objects_per_scene", where, default_objects, low=1,
                                  high=maximum("scene_objects")),
    )


def load_task(name_or_path: str | Path) -> Task:
    """Load ``data/tasks/NAME.toml`` and its object catalogue."""
    path = resolve("tasks", name_or_path)
    table = read_toml(path, "task")
    where = str(path)
    check_keys(table, where, required=("name", "concepts", "objects", "objects_per_scene", "test_scenes"),
               optional=TASK_FIELDS)
    concepts = texts(table, "concepts", where, nonempty=True)
    if len(concepts) > maximum("concepts"):
        raise DataFileError(f"{where}: {len(concepts)} concepts are beyond the limit of {maximum('concepts')} "
                            "concepts a learner tells apart (learning/data/limits.toml)")
    if len(set(concepts)) != len(concepts):
        raise DataFileError(f"{where}: 'concepts' must not repeat a name, got {list(concepts)}")
    objects_path = resolve("objects", text(table, "objects", where))
    kinds = tuple(load_object_kinds(objects_path))
    missing = sorted({k.concept for k in kinds} - set(concepts))
    if missing:
        raise DataFileError(f"{where}: object kinds use concepts not in 'concepts': {missing}")
    uncovered = sorted(set(concepts) - {k.concept for k in kinds})
    if uncovered:
        raise DataFileError(f"{where}: no object kind for concepts {uncovered}")
    count = integer(table, "objects_per_scene", where, low=len(concepts), high=maximum("scene_objects"))
    largest = integer(table, "max_objects_per_scene", where, count, low=count, high=maximum("scene_objects"))
    placement = text(table, "placement", where, "anywhere", choices=("anywhere", "locations"))
    probability = number(table, "state_change_probability", where, 0.0, low=0.0, high=1.0)
    task = Task(
        name=text(table, "name", where),
        description=text(table, "description", where, "", nonempty=False),
        concepts=concepts,
        kinds=kinds,
        objects_per_scene=count,
        test_scenes=integer(table, "test_scenes", where, low=1),
        max_objects_per_scene=largest,
        place_at_locations=placement == "locations",
        state_change_probability=probability,
        relevant_patterns=texts(table, "relevant_features", where, ()),
        datasets=_dataset_plan(section(table, "datasets", where, {}), f"{where} [datasets]", count),
        path=where,
        objects_path=str(objects_path),
    )
    task.relevant_features  # noqa: B018 - validates the names now, with the file in the message
    return task
