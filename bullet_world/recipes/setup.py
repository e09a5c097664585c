"""The ``[recipe_scenes]`` block of a recipe task file: households, lighting and scene variation.

A recipe task file (``data/tasks/serve-pasta.toml``) is an ordinary task file
plus one ``[recipe_scenes]`` table that says how demonstration scenes are built
(thesis §4.3.2): which objects each kitchen's household owns and where each one
lives, which object plays each recipe part there, the two lighting conditions,
and how much the teacher varies the arrangement between demonstrations. Every
problem is reported as a ``DataFileError`` naming the file, the field and what
is accepted. The format is documented in ``docs/recipes.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from bullet_world.camera import Lighting
from bullet_world.catalogue import DATA_DIR, DataFileError, load_task
from bullet_world.datafiles import read_toml

ELSEWHERE = "elsewhere"  # free counter space outside every location the recipe uses
SETUP_FIELDS = ("recipe", "reach", "region_margin", "min_gap", "layouts", "jitter_m", "yaw_jitter",
                "settle_steps", "lighting", "household")
OBJECT_FIELDS = ("kind", "role", "at")


@dataclass(frozen=True)
class HouseholdObject:
    """One object a household owns: its kind, the recipe part it plays ("" for none), where it lives."""

    kind: str
    role: str
    at: str


@dataclass(frozen=True)
class Household:
    """The objects of one kitchen (thesis §4.3.2: each home has its own dishes)."""

    name: str
    kitchens: tuple[str, ...]
    objects: tuple[HouseholdObject, ...]

    def roles(self) -> dict[str, HouseholdObject]:
        return {item.role: item for item in self.objects if item.role}


@dataclass(frozen=True)
class RecipeSceneSetup:
    """Everything needed to build demonstration scenes for one recipe task."""

    task: str
    recipe: str
    reach: tuple[float, float]
    region_margin: float
    min_gap: float
    layouts: int
    jitter_m: float
    yaw_jitter: float
    settle_steps: int
    lighting: dict[str, Lighting]
    households: tuple[Household, ...]
    kinds: frozenset[str] = frozenset()   # the kinds the task's object file has

    def household_for(self, kitchen) -> Household:
        """The household that lives in ``kitchen`` (a name or a :class:`Kitchen`): the kitchen's own
        ``[households.TASK]`` when it carries one, else the one listing its name, else the first."""
        carried = getattr(kitchen, "households", {}).get(self.task)
        if carried is not None:
            where = f"{kitchen.path} [households.{self.task}]"
            entry = {"name": kitchen.name, "kitchens": [kitchen.name], "objects": list(carried)}
            return _household(entry, where, set(self.kinds))
        name = getattr(kitchen, "name", kitchen)
        for household in self.households:
            if name in household.kitchens:
                return household
        return self.households[0]


def load_recipe_setup(name_or_path: str | Path) -> RecipeSceneSetup:
    """Read and check the ``[recipe_scenes]`` block of ``data/tasks/NAME.toml`` (or a path)."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = DATA_DIR / "tasks" / f"{name_or_path}.toml"
    task = load_task(path if path.exists() else name_or_path)  # an unknown name gets the catalogue's message
    table = read_toml(path)
    where = f"{path} [recipe_scenes]"
    if "recipe_scenes" not in table:
        raise DataFileError(f"{path}: task '{task.name}' has no [recipe_scenes] table; it is not a recipe task")
    setup = _field(table, "recipe_scenes", str(path), dict)
    unknown = sorted(set(setup) - set(SETUP_FIELDS))
    if unknown:
        raise DataFileError(f"{where}: unknown field '{unknown[0]}'; accepted: {', '.join(SETUP_FIELDS)}")
    reach = tuple(_field(setup, "reach", where, length=2))
    if not 0 <= reach[0] < reach[1]:
        raise DataFileError(f"{where}: 'reach' must be [near, far] with 0 <= near < far, got {list(reach)}")
    numbers = {key: float(_field(setup, key, where)) for key in
               ("region_margin", "min_gap", "jitter_m", "yaw_jitter")}
    for key, value in numbers.items():
        if value < 0:
            raise DataFileError(f"{where}: '{key}' must be >= 0, got {value}")
    counts = {key: _field(setup, key, where, int) for key in ("layouts", "settle_steps")}
    if counts["layouts"] < 1 or counts["settle_steps"] < 0:
        raise DataFileError(f"{where}: 'layouts' must be >= 1 and 'settle_steps' >= 0, got {counts}")
    kind_names = {kind.name for kind in task.kinds}
    households = tuple(_household(entry, f"{where} household {number}", kind_names)
                       for number, entry in enumerate(_tables(setup, "household", where), 1))
    return RecipeSceneSetup(
        task=task.name, recipe=_field(setup, "recipe", where, str), reach=reach,
        region_margin=numbers["region_margin"], min_gap=numbers["min_gap"], layouts=counts["layouts"],
        jitter_m=numbers["jitter_m"], yaw_jitter=numbers["yaw_jitter"],
        settle_steps=counts["settle_steps"], lighting=_lighting(_field(setup, "lighting", where, dict), where),
        households=households, kinds=frozenset(kind_names),
    )


def _tables(setup: dict, key: str, where: str) -> list[dict]:
    entries = _field(setup, key, where, list)
    if not entries or not all(isinstance(entry, dict) for entry in entries):
        raise DataFileError(f"{where}: '{key}' must be one or more [[recipe_scenes.{key}]] tables")
    return entries


def _lighting(table: dict, where: str) -> dict[str, Lighting]:
    if len(table) < 1:
        raise DataFileError(f"{where}: 'lighting' needs at least one named condition")
    conditions = {}
    for name, entry in table.items():
        here = f"{where} lighting.{name}"
        if not isinstance(entry, dict):
            raise DataFileError(f"{here}: must be a table with direction, ambient, diffuse")
        direction = _field(entry, "direction", here, length=3)
        if direction[2] <= 0:
            raise DataFileError(f"{here}: 'direction' must point up (z > 0) towards the light, got {direction}")
        ambient, diffuse = (float(_field(entry, key, here)) for key in ("ambient", "diffuse"))
        if not (0 <= ambient <= 1 and 0 <= diffuse <= 1):
            raise DataFileError(f"{here}: 'ambient' and 'diffuse' must lie in [0, 1], got {ambient}, {diffuse}")
        norm = sum(value * value for value in direction) ** 0.5
        conditions[name] = Lighting(tuple(value / norm for value in direction), ambient, diffuse)
    return conditions


def _household(entry: dict, where: str, kind_names: set[str]) -> Household:
    name = _field(entry, "name", where, str)
    kitchens = _field(entry, "kitchens", where, list)
    if not all(isinstance(kitchen, str) for kitchen in kitchens):
        raise DataFileError(f"{where}: 'kitchens' must be a list of kitchen names, got {kitchens!r}")
    objects = []
    for number, item in enumerate(_tables(entry, "objects", where), 1):
        here = f"{where} ({name}) object {number}"
        unknown = sorted(set(item) - set(OBJECT_FIELDS))
        if unknown:
            raise DataFileError(f"{here}: unknown field '{unknown[0]}'; accepted: {', '.join(OBJECT_FIELDS)}")
        kind = _field(item, "kind", here, str)
        if kind not in kind_names:
            raise DataFileError(f"{here}: unknown kind '{kind}'; the task's object file has: "
                                f"{', '.join(sorted(kind_names))}")
        role = item.get("role", "")
        if not isinstance(role, str):
            raise DataFileError(f"{here}: 'role' must be a recipe object name, got {role!r}")
        objects.append(HouseholdObject(kind, role, _field(item, "at", here, str)))
    roles = [item.role for item in objects if item.role]
    if len(set(roles)) != len(roles):
        raise DataFileError(f"{where} ({name}): each role may be played by one object only, got {roles}")
    return Household(name, tuple(kitchens), tuple(objects))


def _field(table: dict, key: str, where: str, kind: type | tuple = (int, float), length: int | None = None):
    """``table[key]`` after checking its type (or that it is a list of ``length`` numbers)."""
    if key not in table:
        raise DataFileError(f"{where}: missing field '{key}'")
    value = table[key]
    if length is not None:
        if not isinstance(value, list) or len(value) != length or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value):
            raise DataFileError(f"{where}: '{key}' must be a list of {length} finite numbers, got {value!r}")
        return [float(v) for v in value]
    if not isinstance(value, kind) or isinstance(value, bool):
        expected = kind.__name__ if isinstance(kind, type) else "a number"
        raise DataFileError(f"{where}: '{key}' must be {expected}, got {value!r}")
    if isinstance(value, float) and not math.isfinite(value):
        raise DataFileError(f"{where}: '{key}' must be a finite number, got {value!r}")
    return value
