"""A generated kitchen as a kitchen file: drawn from one seed (``numpy.random.default_rng(seed)``), written in
the shipped kitchens' format with a ``[generated]`` record of where it came from, and loaded back through
:func:`bullet_world.kitchen.load_kitchen` (and its households through the recipe set-up's checks) before it is
kept."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from bullet_world.datafiles import DataFileError, cache_dir
from bullet_world.generation.distributions import Distributions, load_distributions
from bullet_world.generation.layout import Layout, draw_family, draw_layout, location_problem
from bullet_world.generation.rooms import draw_furniture, draw_materials
from bullet_world.kitchen import INTEREST_POINTS, Kitchen, load_kitchen

HEADER = ("# A kitchen drawn by `teachbot world generate` from the seed and the distributions named in [generated]\n"
          "# (docs/kitchen.md#generated-kitchens); the same seed and file give these bytes again. It reads like\n"
          "# bullet_world/data/kitchens/*.toml; [households.TASK] are the dishes its recipes use.\n")


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(round(float(value), 4) + 0.0)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{key} = {_value(item)}" for key, item in value.items()) + " }"
    return "[" + ", ".join(_value(item) for item in value) + "]"


def _table(header: str, fields: dict) -> str:
    return f"\n{header}\n" + "".join(f"{key} = {_value(value)}\n" for key, value in fields.items())


def _lighting(distributions: Distributions, rng: np.random.Generator) -> dict:
    light = distributions.lighting
    azimuth = math.radians(rng.uniform(0.0, 360.0))
    elevation = math.radians(rng.uniform(*light["elevation_degrees"]))
    along = math.cos(elevation) / math.sin(elevation)
    colour_name = str(rng.choice(list(light["colours"])))
    ambient, diffuse = rng.uniform(*light["ambient_low"]), rng.uniform(*light["diffuse_low"])
    return {"direction": [round(along * math.cos(azimuth), 2), round(along * math.sin(azimuth), 2), 1.0],
            "direction_jitter": round(rng.uniform(*light["direction_jitter"]), 2),
            "ambient": [round(ambient, 2), round(ambient + light["ambient_width"], 2)],
            "diffuse": [round(diffuse, 2), round(diffuse + light["diffuse_width"], 2)],
            "colour": list(light["colours"][colour_name]),
            "colour_jitter": round(rng.uniform(*light["colour_jitter"]), 3)}


def _ambient_noise(distributions: Distributions, rng: np.random.Generator) -> dict:
    noise = distributions.ambient_noise
    level, event = rng.uniform(*noise["level_low_db"]), rng.uniform(*noise["event_low_db"])
    return {"level_db": [round(level, 1), round(level + rng.uniform(*noise["level_width_db"]), 1)],
            "events_per_minute": round(rng.uniform(*noise["events_per_minute"]), 1),
            "event_db": [round(event, 1), round(event + rng.uniform(*noise["event_width_db"]), 1)]}


def _households(distributions: Distributions, rng: np.random.Generator) -> dict[str, list[dict]]:
    households = {}
    for task, plan in distributions.households.items():
        objects = [{"kind": str(rng.choice(role["kinds"])), "role": role["role"], "at": role["at"]}
                   for role in plan["roles"]]
        for other in plan["others"]:
            kinds = list(dict.fromkeys(other["kinds"]))
            for index in rng.choice(len(kinds), other["count"], replace=False):
                objects.append({"kind": kinds[int(index)], "at": other["at"]})
        households[task] = objects
    return households


def _described(layout: Layout) -> str:
    """The family's description and the locations seen from the arm, right to left."""
    yaw = math.radians(layout.yaw_degrees)
    def bearing(location):
        dx, dy = location.centre[0] - layout.base[0], location.centre[1] - layout.base[1]
        return math.atan2(-math.sin(yaw) * dx + math.cos(yaw) * dy, math.cos(yaw) * dx + math.sin(yaw) * dy)
    order = sorted(layout.locations.values(), key=bearing)
    return f"{layout.family.description}; seen from the arm, right to left: {', '.join(o.name for o in order)}."


def generate_kitchen(seed: int, distributions: Distributions) -> tuple[str, str]:
    """(name, kitchen file text) of the kitchen drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    family = draw_family(distributions, rng)
    layout = draw_layout(distributions, family, rng, seed)
    parts, fixtures = draw_materials(distributions, rng)
    furniture = draw_furniture(layout, distributions, parts, rng)
    lighting, noise = _lighting(distributions, rng), _ambient_noise(distributions, rng)
    households = _households(distributions, rng)
    name = f"{distributions.name_prefix}-{seed}"
    used = [parts["worktop"], parts["floor"], parts["cabinets"], parts["doors"], parts["handles"],
            *(material for fixture in fixtures.values() for material in fixture[1:]),
            *(piece["material"] for piece in furniture)]
    text = HEADER + f"name = {_value(name)}\ndescription = {_value(_described(layout))}\n"
    text += _table("[generated]", {"seed": seed, "family": family.name, "distributions": distributions.path.name,
                                   "sha256": distributions.sha256})
    text += _table("[counter]", {"size": [layout.length, layout.depth, distributions.worktop["thickness"]],
                                 "centre": [0.0, 0.0], "colour": list(distributions.materials[parts["worktop"]])})
    text += _table("[robot]", {"base": [*layout.base, 0.0], "yaw_degrees": layout.yaw_degrees})
    text += _table("[object_region]", layout.region)
    text += _table("[camera]", layout.camera)
    text += _table("[lighting]", lighting) + _table("[ambient_noise]", noise)
    for location_name in INTEREST_POINTS:
        location = layout.locations[location_name]
        kind, material, accent = fixtures[location_name]
        text += _table(f"[locations.{location_name}]", {"centre": list(location.centre),
                                                       "half_size": list(location.half_size), "fixture": kind,
                                                       "material": material, "accent": accent})
    text += _table("[materials]", {material: list(distributions.materials[material])
                                   for material in dict.fromkeys(used)})
    text += _table("[room]", {"worktop_height": layout.worktop_height, "floor": parts["floor"],
                              "cabinets": parts["cabinets"], "doors": parts["doors"], "handles": parts["handles"]})
    for piece in furniture:
        text += _table("[[furniture]]", piece)
    for task, objects in households.items():
        text += f"\n[households.{task}]\nobjects = [\n" + "".join(f"    {_value(item)},\n" for item in objects) + "]\n"
    return name, text


def check_generated(kitchen: Kitchen, distributions: Distributions, where: str) -> None:
    """What load_kitchen does not know: every location within the generator's reach band, and every household
    accepted by its recipe task's checks."""
    from bullet_world.recipes.setup import load_recipe_setup

    x, y = kitchen.region_x, kitchen.region_y
    region = {"x": x, "y": y}
    length, depth, _ = kitchen.counter_size
    for location in kitchen.locations.values():
        problem = location_problem(location, distributions, length, depth, kitchen.robot_base[:2],
                                   math.degrees(kitchen.robot_yaw), region)
        if problem:
            raise DataFileError(f"{where} [locations.{location.name}]: {problem}")
    for task in kitchen.households:
        load_recipe_setup(task).household_for(kitchen)


def generate_kitchens(seed: int, count: int, folder: str | Path, distributions_path: str | Path | None = None,
                      ) -> list[Path]:
    """Write the kitchens of seeds ``seed`` .. ``seed + count - 1`` to ``folder`` (checked before each is kept)."""
    distributions = load_distributions(distributions_path)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for each in range(seed, seed + count):
        name, text = generate_kitchen(each, distributions)
        path = folder / f"{name}.toml"
        draft = folder / f".{name}.{os.getpid()}.toml"
        draft.write_text(text, encoding="utf-8")
        try:
            check_generated(load_kitchen(draft), distributions, str(path))
        except DataFileError as error:
            draft.unlink()
            raise DataFileError(f"seed {each}: the drawn kitchen fails its checks: {error}") from None
        os.replace(draft, path)
        written.append(path)
    return written


def cached_kitchens(first: int, last: int, distributions_path: str | Path | None = None) -> list[str]:
    """The kitchens of seeds ``first`` .. ``last`` as files in the cache (``<cache>/kitchens/<distributions
    sha256[:12]>/``), written once: what a suite's ``kitchens = { generated = [FIRST, LAST] }`` names."""
    distributions = load_distributions(distributions_path)
    folder = cache_dir() / "kitchens" / distributions.sha256[:12]
    paths = []
    for seed in range(first, last + 1):
        path = folder / f"generated-{seed}.toml"
        if not path.exists():
            generate_kitchens(seed, 1, folder, distributions.path)
        paths.append(str(path))
    return paths
