"""The room around a generated kitchen's worktop (its ``[materials]``, ``[room]`` and ``[[furniture]]``): walls,
the back run or wings of its layout family, a sink, upper cabinets beside (never over) the arm, the arm's
pedestal, and the materials of every part and fixture, drawn from the generator's palette."""

from __future__ import annotations

import numpy as np

from bullet_world.generation.distributions import Distributions
from bullet_world.generation.layout import Layout, metres


def draw_materials(distributions: Distributions, rng: np.random.Generator) -> tuple[dict, dict]:
    """(part -> material name for every palette part, location -> (fixture, material, accent))."""
    parts = {part: str(rng.choice(choices)) for part, choices in distributions.palette.items()}
    fixtures = {location: (entry["fixture"], str(rng.choice(entry["material"])), str(rng.choice(entry["accent"])))
                for location, entry in distributions.locations.items()}
    return parts, fixtures


def _piece(name: str, low, high, material: str, shape: str = "box", collision: bool = True) -> dict:
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    piece = {"name": name, "shape": shape, "centre": [metres(v) for v in (low + high) / 2],
             "size": [metres(v) for v in high - low], "material": material}
    if not collision:
        piece["collision"] = False
    return piece


def _run(name: str, low_xy, high_xy, floor: float, thickness: float, parts: dict) -> list[dict]:
    """A run of base cabinets with its own worktop, flush with the arm's worktop."""
    return [_piece(f"{name} cabinets", (*low_xy, floor), (*high_xy, -thickness), parts["cabinets"]),
            _piece(f"{name} worktop", (*low_xy, -thickness), (*high_xy, 0.0), parts["worktop"])]


def _sink(name: str, centre_xy, tap_xy, distributions: Distributions, parts: dict) -> list[dict]:
    width, depth = distributions.runs["sink"]
    low, high = np.subtract(centre_xy, (width / 2, depth / 2)), np.add(centre_xy, (width / 2, depth / 2))
    return [_piece(f"{name} sink", (*low, -0.002), (*high, 0.001), parts["fittings"], collision=False),
            _piece(f"{name} tap", (tap_xy[0] - 0.015, tap_xy[1] - 0.015, 0.0),
                   (tap_xy[0] + 0.015, tap_xy[1] + 0.015, 0.24), parts["fittings"], shape="cylinder")]


def draw_furniture(layout: Layout, distributions: Distributions, parts: dict, rng: np.random.Generator) -> list:
    """Every [[furniture]] piece of the layout's family, in a fixed order."""
    family, runs, worktop = layout.family, distributions.runs, distributions.worktop
    floor = -layout.worktop_height
    half_length, half_depth = layout.length / 2, layout.depth / 2
    base_x, base_y = layout.base
    width, depth = worktop["pedestal"]
    pieces = [_piece("robot pedestal", (base_x - width / 2, -half_depth - depth, floor),
                     (base_x + width / 2, -half_depth, 0.0), parts["doors"])]
    back_gap = float(rng.uniform(*family.ranges["back_gap"]))
    run_front = base_y - back_gap if family.back_run else base_y - back_gap + runs["depth"]
    wall_y = run_front - runs["depth"]
    side_gap = float(rng.uniform(*family.ranges["side_wall_gap"]))
    sides = [-1, 1] if family.side_walls == 2 or family.wings == 2 else [int(rng.choice([-1, 1]))]
    wall_sides = sides[:family.side_walls] if family.side_walls < 2 else [-1, 1]
    wall_x = half_length + side_gap
    span = (-wall_x, wall_x) if family.side_walls == 2 else (-half_length - 1.0, half_length + 1.0)
    if family.side_walls == 1:
        span = (-wall_x, half_length + 1.0) if wall_sides[0] < 0 else (-half_length - 1.0, wall_x)
    wall_top = runs["wall_height"] + floor
    pieces.append(_piece("back wall", (span[0], wall_y - 0.04, floor), (span[1], wall_y, wall_top), parts["walls"]))
    for side in wall_sides:
        x = side * (wall_x + 0.02)
        pieces.append(_piece(f"{'left' if side < 0 else 'right'} wall", (x - 0.02, wall_y, floor),
                             (x + 0.02, half_depth + 0.8, wall_top), parts["walls"]))
    if family.back_run:
        pieces += _back_run(layout, distributions, parts, rng, span, run_front, wall_y, floor)
    for side in sides[:family.wings]:
        pieces += _wing(layout, distributions, parts, side, wall_y, floor)
    return pieces


def _back_run(layout, distributions, parts, rng, span, run_front, wall_y, floor) -> list[dict]:
    """Cabinets and worktop along the back wall, a sink away from the arm, uppers either side of it, and
    perhaps a tall fridge-freezer at one end."""
    runs, thickness = distributions.runs, distributions.worktop["thickness"]
    base_x = layout.base[0]
    left, right = max(span[0], -layout.length / 2 - 0.4), min(span[1], layout.length / 2 + 0.4)
    tall = rng.random() < layout.family.tall_unit
    tall_side = int(rng.choice([-1, 1]))
    tall_width = runs["tall_unit"][0]
    if tall:   # the fridge-freezer stands at one end of the run, the run stops short of it
        left, right = (left + tall_width + 0.02, right) if tall_side < 0 else (left, right - tall_width - 0.02)
    pieces = _run("back run", (left, wall_y), (right, run_front), floor, thickness, parts)
    sink_side = 1 if base_x < 0 else -1
    sink_x = base_x + sink_side * float(rng.uniform(0.55, 0.75))
    sink_x = min(max(sink_x, left + 0.35), right - 0.35)
    pieces += _sink("back run", (sink_x, (wall_y + run_front) / 2), (sink_x, wall_y + 0.08), distributions, parts)
    low, high = runs["upper_height"]
    clearance = runs["upper_clearance"]
    for name, (a, b) in (("upper cabinets left", (left, base_x - clearance)),
                         ("upper cabinets right", (base_x + clearance, right))):
        if b - a >= 0.3:
            pieces.append(_piece(name, (a, wall_y, low), (b, wall_y + runs["upper_depth"], high), parts["uppers"]))
    if tall:
        x = left - tall_width - 0.02 if tall_side < 0 else right + 0.02
        size = runs["tall_unit"]
        pieces.append(_piece("fridge-freezer", (x, wall_y, floor), (x + size[0], wall_y + size[1], floor + size[2]),
                             parts["fittings"]))
    return pieces


def _wing(layout, distributions, parts, side: int, wall_y: float, floor: float) -> list[dict]:
    """A run turning from one end of the worktop towards the back wall, with a sink and uppers over it."""
    runs, thickness = distributions.runs, distributions.worktop["thickness"]
    inner, outer = side * layout.length / 2, side * (layout.length / 2 + runs["depth"])
    low_x, high_x = min(inner, outer), max(inner, outer)
    name = f"{'left' if side < 0 else 'right'} wing"
    back_edge = layout.depth / 2
    pieces = _run(name, (low_x, wall_y), (high_x, back_edge), floor, thickness, parts)
    middle_y = (wall_y + back_edge) / 2
    pieces += _sink(name, ((low_x + high_x) / 2, middle_y), (outer - side * 0.08, middle_y), distributions, parts)
    low, high = runs["upper_height"]
    wall_x = outer + side * 0.02
    upper = sorted((wall_x, wall_x - side * runs["upper_depth"]))
    pieces.append(_piece(f"{name} uppers", (upper[0], wall_y, low), (upper[1], back_edge - 0.1, high),
                         parts["uppers"]))
    return pieces
