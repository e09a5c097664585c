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

from bullet_world.datafiles import (
    DATA_DIR,
    DataFileError,
    colour_list,
    number_range,
    optional,
    read_toml,
    resolve,
    string_list,
)
from bullet_world.datafiles import field as table_field
from bullet_world.kitchen import INTEREST_POINTS, Kitchen, Location, load_kitchen

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


def _state(table: dict, name: str, where: str, defaults: dict) -> KindState:
    """One state from ``table``; fields it leaves out come from ``defaults`` (the kind's own fields)."""
    merged = {**defaults, **table}
    shape = table_field(merged, "shape", where, str)
    if shape not in SHAPES:
        raise DataFileError(f"{where}: shape '{shape}' is not one of {', '.join(SHAPES)}")
    texture = optional(merged, "texture", where, "plain", str)
    if texture not in TEXTURES:
        raise DataFileError(f"{where}: texture '{texture}' is not one of {', '.join(TEXTURES)}")
    profile: tuple = ()
    if shape == "lathe":
        points = table_field(merged, "profile", where, list)
        if len(points) < 2:
            raise DataFileError(f"{where}: 'profile' needs at least two [radius, height] points")
        profile = tuple(tuple(table_field({"profile": p}, "profile", where, length=2)) for p in points)
        heights = [p[1] for p in profile]
        if heights != sorted(heights) or heights[0] != 0.0 or heights[-1] != 1.0 or \
                not all(0.0 <= p[0] <= 1.0 for p in profile):
            raise DataFileError(f"{where}: 'profile' points must rise from height 0 to 1 with radii in 0..1")
    fill = float(optional(merged, "fill", where, 0.0))
    if not 0.0 <= fill < 1.0:
        raise DataFileError(f"{where}: 'fill' must be in [0, 1), got {fill}")
    count = int(optional(merged, "count", where, 3, int))
    if not 1 <= count <= 8:
        raise DataFileError(f"{where}: 'count' must be 1..8 slices, got {count}")
    location = optional(merged, "location", where, None, str)
    if location is not None and location not in INTEREST_POINTS:
        raise DataFileError(f"{where}: location '{location}' is not one of {', '.join(INTEREST_POINTS)}")
    return KindState(
        name=name, shape=shape, dimensions={key: number_range(merged, key, where) for key in SHAPES[shape]},
        colours=colour_list(merged, "colours", where), colour_jitter=float(table_field(merged, "colour_jitter", where)),
        mass=number_range(merged, "mass", where), texture=texture,
        inner_colour=tuple(optional(merged, "inner_colour", where, [0.9, 0.85, 0.7], length=3)),
        location=location, profile=profile, open_top=bool(optional(merged, "open", where, False, bool)),
        fill=fill, count=count,
    )


def load_object_kinds(name_or_path: str | Path) -> list[ObjectKind]:
    """Load a catalogue of object kinds from ``data/objects/NAME.toml`` (or a path)."""
    path = resolve("objects", name_or_path)
    kinds = read_toml(path).get("kind")
    if not isinstance(kinds, list) or not kinds:
        raise DataFileError(f"{path}: needs at least one [[kind]] table")
    result = []
    for index, table in enumerate(kinds):
        where = f"{path}: kind {index + 1}"
        name = table_field(table, "name", where, str)
        defaults = {key: value for key, value in table.items() if key not in ("state", "name", "concept", "kitchens")}
        state_tables = table.get("state", [])
        if not isinstance(state_tables, list):
            raise DataFileError(f"{where}: states must be [[kind.state]] tables")
        if state_tables:
            states = tuple(_state(entry, table_field(entry, "name", f"{where} state {i + 1}", str),
                                  f"{where} ({name}) state {i + 1}", defaults)
                           for i, entry in enumerate(state_tables))
        else:
            states = (_state({}, "as-is", f"{where} ({name})", defaults),)
        first = states[0]
        result.append(ObjectKind(
            name=name, concept=table_field(table, "concept", where, str), shape=first.shape,
            dimensions=first.dimensions, colours=first.colours, colour_jitter=first.colour_jitter, mass=first.mass,
            states=states, kitchens=string_list(table, "kitchens", where),
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
    plan = DatasetPlan(
        pools=int(optional(table, "pools", where, 5, int)),
        pool_size=int(optional(table, "pool_size", where, 400, int)),
        test_size=int(optional(table, "test_size", where, 200, int)),
        objects_per_scene=int(optional(table, "objects_per_scene", where, default_objects, int)),
    )
    if min(plan.pools, plan.pool_size, plan.test_size, plan.objects_per_scene) < 1:
        raise DataFileError(f"{where}: pools, pool_size, test_size and objects_per_scene must be at least 1")
    return plan


def load_task(name_or_path: str | Path) -> Task:
    """Load ``data/tasks/NAME.toml`` and its object catalogue."""
    path = resolve("tasks", name_or_path)
    table = read_toml(path)
    where = str(path)
    concepts = tuple(table_field(table, "concepts", where, list))
    objects_path = resolve("objects", table_field(table, "objects", where, str))
    kinds = tuple(load_object_kinds(objects_path))
    missing = sorted({k.concept for k in kinds} - set(concepts))
    if missing:
        raise DataFileError(f"{where}: object kinds use concepts not in 'concepts': {missing}")
    uncovered = sorted(set(concepts) - {k.concept for k in kinds})
    if uncovered:
        raise DataFileError(f"{where}: no object kind for concepts {uncovered}")
    count = table_field(table, "objects_per_scene", where, int)
    if count < len(concepts):
        raise DataFileError(f"{where}: 'objects_per_scene' must be at least the number of concepts ({len(concepts)})")
    largest = int(optional(table, "max_objects_per_scene", where, count, int))
    if largest < count:
        raise DataFileError(f"{where}: 'max_objects_per_scene' ({largest}) is below 'objects_per_scene' ({count})")
    placement = optional(table, "placement", where, "anywhere", str)
    if placement not in ("anywhere", "locations"):
        raise DataFileError(f"{where}: 'placement' must be 'anywhere' or 'locations', got '{placement}'")
    probability = float(optional(table, "state_change_probability", where, 0.0))
    if not 0.0 <= probability <= 1.0:
        raise DataFileError(f"{where}: 'state_change_probability' must be in 0..1, got {probability}")
    task = Task(
        name=table_field(table, "name", where, str),
        description=table.get("description", ""),
        concepts=concepts,
        kinds=kinds,
        objects_per_scene=count,
        test_scenes=table_field(table, "test_scenes", where, int),
        max_objects_per_scene=largest,
        place_at_locations=placement == "locations",
        state_change_probability=probability,
        relevant_patterns=string_list(table, "relevant_features", where),
        datasets=_dataset_plan(table.get("datasets", {}), f"{where} [datasets]", count),
        path=where,
        objects_path=str(objects_path),
    )
    task.relevant_features  # noqa: B018 - validates the names now, with the file in the message
    return task
