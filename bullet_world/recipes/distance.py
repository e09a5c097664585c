"""How different two kitchens are for one recipe (issue 52's transfer study, docs/kitchen-transfer-plan.toml).

The thesis's edit distance (eq. 4.4) compares two demonstrations within one kitchen: how far every object must
move to turn one arrangement into the other. Between kitchens the analogue is what must change to turn one
kitchen's demonstrations of a recipe into the other's: where the recipe's locations are, seen from the robot
(where the recipe's parameters are learned), and what the dishes that play its roles look like:

    d(A, B) = sum over the recipe's locations of |centre_A - centre_B| / unit  +  sum over its roles of [kind differs]

with the centres in the robot's frame (forward, left) and ``unit`` 0.10 m, both fixed by the plan before any
number was seen.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bullet_world.kitchen import Kitchen, load_kitchen
from bullet_world.recipes.setup import load_recipe_setup

DISPLACEMENT_UNIT_M = 0.10


@dataclass(frozen=True)
class KitchenDistance:
    """``displacement``: the summed moves of the recipe's locations in units; ``appearance``: roles whose
    household kind differs; ``total``: their sum (the plan's d)."""

    displacement: float
    appearance: int

    @property
    def total(self) -> float:
        return self.displacement + self.appearance


def location_centres(kitchen: Kitchen, names: Sequence[str]) -> np.ndarray:
    """The (forward, left) centres of the named locations in the robot's frame."""
    c, s = np.cos(kitchen.robot_yaw), np.sin(kitchen.robot_yaw)
    offsets = np.array([kitchen.locations[n].centre[:2] for n in names], dtype=float) - kitchen.robot_base[:2]
    return np.column_stack([c * offsets[:, 0] + s * offsets[:, 1], -s * offsets[:, 0] + c * offsets[:, 1]])


def kitchen_distance(steps: Sequence[tuple[str, str, str]], task: str, first: str | Kitchen, second: str | Kitchen,
                     unit: float = DISPLACEMENT_UNIT_M) -> KitchenDistance:
    """The plan's distance between two kitchens (names, paths or loaded) for a recipe given as (object, start,
    end) triples of ``task``, whose roles are the steps' objects."""
    a, b = (k if isinstance(k, Kitchen) else load_kitchen(k) for k in (first, second))
    names = list(dict.fromkeys(place for _, start, end in steps for place in (start, end)))
    missing = [(k.name, n) for k in (a, b) for n in names if n not in k.locations]
    if missing:
        raise ValueError(f"kitchen '{missing[0][0]}' has no location '{missing[0][1]}' that the recipe uses")
    moved = np.linalg.norm(location_centres(a, names) - location_centres(b, names), axis=1).sum() / unit
    setup = load_recipe_setup(task)
    roles_a, roles_b = setup.household_for(a).roles(), setup.household_for(b).roles()
    roles = list(dict.fromkeys(role for role, _, _ in steps))
    differs = sum(roles_a[r].kind != roles_b[r].kind for r in roles)
    return KitchenDistance(float(moved), int(differs))
