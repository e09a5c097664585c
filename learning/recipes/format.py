"""Task recipes as sequences of parameterised actions (thesis §4.2.1).

A recipe is an ordered list of primitive actions. The only action so far is
``pick-place <object, start-location, end-location>``: take the *object* found
at the *start* location and put it at the *end* location. The robot does not
know what the names mean in a given kitchen; it grounds each distinct object
and location name from demonstrations (see ``learning.recipes.grounding``).

Recipe file format (TOML)
-------------------------
::

    name = "serve-pasta"                 # required, non-empty string
    description = "Bring the pasta..."   # optional string, default ""

    [[step]]                             # one table per action, in order
    action = "pick-place"                # required; accepted: pick-place
    object = "pasta-pot"                 # required, non-empty string
    start = "stove"                      # required, non-empty string
    end = "counter"                      # required, non-empty string

At least one ``[[step]]`` is required. Any other key is rejected so a typo
does not pass silently. A name may be used as an object or as a location,
never both in one recipe. The built-in recipes live in ``learning/recipes/data/``
(``serve-pasta`` and ``serve-salad``, thesis Tables 4.1 and 4.2).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from learning.datafiles import check_keys, read_toml
from learning.errors import DataFileError

PICK_PLACE = "pick-place"
ACCEPTED_ACTIONS: tuple[str, ...] = (PICK_PLACE,)
RECIPE_FIELDS: tuple[str, ...] = ("name", "description", "step")
STEP_FIELDS: tuple[str, ...] = ("action", "object", "start", "end")
BUILTIN_RECIPE_DIR = Path(__file__).resolve().parent / "data"


@dataclass(frozen=True)
class RecipeStep:
    """One parameterised action ``action <object, start, end>`` (thesis §4.2.1)."""

    action: str
    object: str
    start: str
    end: str

    def __str__(self) -> str:
        return f"{self.action} <{self.object}, {self.start}, {self.end}>"


@dataclass(frozen=True)
class Recipe:
    """A named task recipe: an ordered tuple of steps (thesis Tables 4.1, 4.2)."""

    name: str
    description: str
    steps: tuple[RecipeStep, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "steps", tuple(self.steps))
        problem = _first_problem_in_recipe(self.name, self.steps)
        if problem is not None:
            raise ValueError(f"recipe {self.name!r}: {problem}")


@dataclass(frozen=True)
class RecipeParameters:
    """The distinct parameter names of a recipe, in order of first use."""

    objects: tuple[str, ...]
    locations: tuple[str, ...]


def recipe_parameters(recipe: Recipe) -> RecipeParameters:
    """Distinct object and location parameters P_t of a recipe (thesis §4.2.1)."""
    objects: dict[str, None] = {}
    locations: dict[str, None] = {}
    for step in recipe.steps:
        objects.setdefault(step.object, None)
        locations.setdefault(step.start, None)
        locations.setdefault(step.end, None)
    return RecipeParameters(objects=tuple(objects), locations=tuple(locations))


def load_recipe(path: str | Path) -> Recipe:
    """Read and validate a recipe TOML file; bad content raises a one-line DataFileError (a ValueError)."""
    return recipe_from_mapping(read_toml(path, "recipe"), source=str(path))


def recipe_from_mapping(data: dict[str, Any], source: str = "recipe") -> Recipe:
    """Build a Recipe from parsed TOML; ``source`` names the origin in error messages."""
    if not isinstance(data, dict):
        raise DataFileError(f"{source}: expected a table of fields, got {type(data).__name__}")
    check_keys(data, source, optional=RECIPE_FIELDS)
    name = _required_text(data, "name", source)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise DataFileError(f"{source}: field 'description' must be a string, got {type(description).__name__}")
    if "step" not in data:
        raise DataFileError(f"{source}: missing field 'step'; a recipe needs at least one [[step]] table")
    raw_steps = data["step"]
    if not isinstance(raw_steps, list) or not all(isinstance(s, dict) for s in raw_steps):
        raise DataFileError(f"{source}: field 'step' must be an array of [[step]] tables, "
                            f"got {type(raw_steps).__name__}")
    if not raw_steps:
        raise DataFileError(f"{source}: field 'step' is empty; a recipe needs at least one step")
    steps = tuple(_step_from_mapping(raw, f"{source}: step {number}") for number, raw in enumerate(raw_steps, start=1))
    problem = _first_problem_in_recipe(name, steps)
    if problem is not None:
        raise DataFileError(f"{source}: {problem}")
    return Recipe(name=name, description=description, steps=steps)


def builtin_recipe_names() -> list[str]:
    """Names of the recipes shipped in ``learning/recipes/data/``, sorted."""
    return sorted(path.stem for path in BUILTIN_RECIPE_DIR.glob("*.toml"))


def load_builtin_recipe(name: str) -> Recipe:
    """Load a shipped recipe by name, e.g. ``"serve-pasta"``."""
    names = builtin_recipe_names()
    if name not in names:
        raise DataFileError(f"unknown built-in recipe {name!r}; accepted: {', '.join(names)}")
    return load_recipe(BUILTIN_RECIPE_DIR / f"{name}.toml")


def _step_from_mapping(raw: dict[str, Any], where: str) -> RecipeStep:
    check_keys(raw, where, optional=STEP_FIELDS)
    values = {field_name: _required_text(raw, field_name, where) for field_name in STEP_FIELDS}
    if values["action"] not in ACCEPTED_ACTIONS:
        raise DataFileError(
            f"{where}: unknown action {values['action']!r}; accepted actions: {', '.join(ACCEPTED_ACTIONS)}"
        )
    return RecipeStep(**values)


def _required_text(mapping: dict[str, Any], field_name: str, where: str) -> str:
    if field_name not in mapping:
        raise DataFileError(f"{where}: missing field {field_name!r} (a non-empty string)")
    value = mapping[field_name]
    if not isinstance(value, str):
        raise DataFileError(
            f"{where}: field {field_name!r} must be a non-empty string, got {type(value).__name__} {value!r}"
        )
    if not value.strip() or value != value.strip():
        raise DataFileError(
            f"{where}: field {field_name!r} is {value!r}; accepted: a non-empty string without surrounding spaces"
        )
    return value


def _first_problem_in_recipe(name: object, steps: tuple[object, ...]) -> str | None:
    """Checks shared by the dataclass and the file loader; None when the recipe is sound."""
    if not isinstance(name, str) or not name.strip():
        return "the name must be a non-empty string"
    if not steps:
        return "a recipe needs at least one step"
    checked: list[RecipeStep] = []
    for number, step in enumerate(steps, start=1):
        if not isinstance(step, RecipeStep):
            return f"step {number} must be a RecipeStep, got {type(step).__name__}"
        if step.action not in ACCEPTED_ACTIONS:
            return f"step {number}: unknown action {step.action!r}; accepted actions: {', '.join(ACCEPTED_ACTIONS)}"
        checked.append(step)
    objects = {step.object for step in checked}
    locations = {step.start for step in checked} | {step.end for step in checked}
    both = sorted(objects & locations)
    if both:
        return (
            f"{both[0]!r} is used both as an object and as a location; "
            "accepted: each name is either an object or a location"
        )
    return None
