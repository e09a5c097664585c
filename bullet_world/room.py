"""The room around a kitchen's counter (``[materials]``, ``[room]``, ``[[furniture]]`` and each location's
``fixture`` in ``data/kitchens``): floor, base cabinets, walls, decoration, and the fixture every semantic
location is built as (a cooktop, a fridge tray, shelving, a cabinet top, a cutting board).

Everything is described as :class:`Piece` primitives (boxes and cylinders) in the world frame, worked out
here from the data alone; :mod:`bullet_world.world` turns them into static PyBullet bodies. The fixture tops
lie flat on the worktop (their top :data:`FIXTURE_TOP_M` above it, without collision), so objects stand
on the counter exactly as before and a location is exactly the area the kitchen file gives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from learning.datafiles import check_keys, flag, number, numbers, tables, text
from learning.errors import DataFileError

FIXTURE_KINDS = ("cooktop", "fridge", "shelf", "cabinet", "cutting-board")
SHAPES = ("box", "cylinder")
FIXTURE_TOP_M = 0.0005       # fixture tops: this far above the worktop (drawn over it, never under objects)
BURNER_TOP_M = 0.0015        # burner rings on a cooktop
PLINTH_M = 0.10              # toe kick under the base cabinets
CARCASS_INSET_M = 0.03       # base cabinets stand this far inside the worktop's edge
DOOR_WIDTH_M = 0.45          # base cabinet doors along every edge of the worktop
FLUSH_M = 0.002              # a piece whose top is at most this far above the worktop lies on it (no reach check)


@dataclass(frozen=True)
class Piece:
    """One primitive of the room: a box (``size`` = full x, y, z) or an upright cylinder (``size`` =
    diameter, diameter, height), centred at ``centre``, in a colour; ``collision``: the arm and objects
    bump into it."""

    name: str
    shape: str
    centre: tuple[float, float, float]
    size: tuple[float, float, float]
    colour: tuple[float, float, float]
    collision: bool = True

    @property
    def top(self) -> float:
        return self.centre[2] + self.size[2] / 2

    def footprint_points(self, step: float = 0.02) -> np.ndarray:
        """Points (n, 2) covering the piece's footprint (its x-y box), ``step`` apart."""
        axes = [np.linspace(c - s / 2, c + s / 2, max(2, int(np.ceil(s / step)) + 1))
                for c, s in zip(self.centre[:2], self.size[:2])]
        gx, gy = np.meshgrid(*axes)
        return np.column_stack([gx.ravel(), gy.ravel()])


@dataclass(frozen=True)
class Fixture:
    """What a semantic location is built as: ``kind`` (one of :data:`FIXTURE_KINDS`), the colour of its top
    and of its details (burners, handles, shelf backs)."""

    kind: str
    colour: tuple[float, float, float]
    accent: tuple[float, float, float]


@dataclass(frozen=True)
class Room:
    """Floor, base cabinets and free-standing furniture (walls, uppers, sink...) of one kitchen."""

    worktop_height: float                     # the worktop's top (z = 0) above the floor
    floor_colour: tuple[float, float, float]
    cabinet_colour: tuple[float, float, float]
    door_colour: tuple[float, float, float]
    handle_colour: tuple[float, float, float]
    furniture: tuple[Piece, ...]


def read_materials(table: dict, where: str) -> dict[str, tuple[float, float, float]]:
    """``[materials]``: name = [r, g, b] (channels in 0..1)."""
    if not isinstance(table, dict):
        raise DataFileError(f"{where}: must be a table of material = [r, g, b], got {table!r}")
    return {name: numbers(table, name, where, length=3, low=0.0, high=1.0) for name in table}


def material(table: dict, key: str, where: str, materials: dict, default=None) -> tuple[float, float, float]:
    """The colour of the material named by ``table[key]``."""
    name = text(table, key, where, default)
    if name is None:
        return default
    if name not in materials:
        known = ", ".join(sorted(materials)) or "none (add a [materials] table)"
        raise DataFileError(f"{where}: '{key}' names the unknown material '{name}'; materials: {known}")
    return materials[name]


def read_fixture(table: dict, where: str, materials: dict) -> Fixture | None:
    """A location's ``fixture``, ``material`` and ``accent`` (None when the location names no fixture)."""
    if "fixture" not in table:
        for key in ("material", "accent"):
            if key in table:
                raise DataFileError(f"{where}: '{key}' needs a 'fixture' (one of {', '.join(FIXTURE_KINDS)})")
        return None
    kind = text(table, "fixture", where, choices=FIXTURE_KINDS)
    return Fixture(kind, material(table, "material", where, materials), material(table, "accent", where, materials))


def read_room(table: dict, where: str, materials: dict, furniture: list, kitchen_where: str) -> Room:
    """``[room]`` (floor, cabinets, doors, handles, worktop height) and the ``[[furniture]]`` list."""
    check_keys(table, where, required=("worktop_height", "floor", "cabinets", "doors", "handles"))
    pieces = []
    for index, entry in enumerate(furniture):
        at = f"{kitchen_where} [[furniture]] {index + 1}"
        check_keys(entry, at, required=("name", "shape", "centre", "size", "material"), optional=("collision",))
        shape = text(entry, "shape", at, choices=SHAPES)
        size = numbers(entry, "size", at, length=3, above=0.0)
        if shape == "cylinder" and size[0] != size[1]:
            raise DataFileError(f"{at}: a cylinder's 'size' is [diameter, diameter, height]; got {list(size)}")
        pieces.append(Piece(text(entry, "name", at), shape, numbers(entry, "centre", at, length=3), size,
                            material(entry, "material", at, materials), flag(entry, "collision", at, True)))
    return Room(number(table, "worktop_height", where, above=0.2, below=2.0),
                material(table, "floor", where, materials), material(table, "cabinets", where, materials),
                material(table, "doors", where, materials), material(table, "handles", where, materials),
                tuple(pieces))


def furniture_list(table: dict, where: str) -> list:
    return tables(table, "furniture", where, [])


# -- geometry ------------------------------------------------------------------------------------------------
def _box(name, low, high, colour, collision=True) -> Piece:
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    return Piece(name, "box", tuple((low + high) / 2), tuple(high - low), colour, collision)


def nearest_edge(xy, counter_centre, counter_half) -> tuple[int, int]:
    """(axis, side) of the worktop edge nearest to ``xy``: axis 0 is x, side +1 the high edge."""
    offset = np.asarray(xy[:2], dtype=float) - np.asarray(counter_centre)
    gaps = [(counter_half[axis] - side * offset[axis], axis, side) for axis in (0, 1) for side in (-1, 1)]
    _, axis, side = min(gaps)
    return axis, side


def _front(name, along: tuple[float, float], axis: int, side: int, counter_centre, counter_half, z: tuple,
           colour, depth: float = 0.02) -> Piece:
    """A vertical panel on the worktop's edge (``axis``, ``side``), spanning ``along`` on the other axis."""
    edge = counter_centre[axis] + side * counter_half[axis]
    low, high = [0.0, 0.0, z[0]], [0.0, 0.0, z[1]]
    low[axis], high[axis] = sorted((edge - side * depth, edge - side * 0.001))
    low[1 - axis], high[1 - axis] = along
    return _box(name, low, high, colour)


def _handle(name, panel: Piece, axis: int, side: int, colour) -> Piece:
    """A bar handle just below the top of a front panel."""
    centre = list(panel.centre)
    centre[axis] += side * (panel.size[axis] / 2 + 0.01)
    centre[2] = panel.top - 0.06
    size = [0.02, 0.02, 0.02]
    size[1 - axis] = min(0.25, 0.6 * panel.size[1 - axis])
    return Piece(name, "box", tuple(centre), tuple(size), colour)


def fixture_pieces(name: str, location, fixture: Fixture, counter_centre, counter_half, thickness: float,
                   floor_z: float) -> list[Piece]:
    """The pieces of one location's fixture: its top (exactly the location's area) and its details, plus
    the front it shows on the nearest edge of the worktop (oven door, fridge door, open shelves, cupboard)."""
    cx, cy = location.centre[:2]
    hx, hy = location.half_size
    top = _box(f"{name} {fixture.kind}", (cx - hx, cy - hy, -0.002), (cx + hx, cy + hy, FIXTURE_TOP_M),
               fixture.colour, collision=False)
    pieces = [top]
    axis, side = nearest_edge((cx, cy), counter_centre, counter_half)
    along = (location.centre[1 - axis] - location.half_size[1 - axis] - 0.02,
             location.centre[1 - axis] + location.half_size[1 - axis] + 0.02)
    below = (floor_z + PLINTH_M, -thickness - 0.01)
    front = _front(f"{name} front", along, axis, side, counter_centre, counter_half, below, fixture.colour)
    if fixture.kind == "cooktop":
        radius = 0.32 * min(hx, hy)
        for i, (dx, dy) in enumerate(((-1, -1), (1, -1), (-1, 1), (1, 1))):
            pieces.append(Piece(f"{name} burner {i + 1}", "cylinder", (cx + dx * hx / 2, cy + dy * hy / 2,
                                (BURNER_TOP_M - 0.002) / 2), (2 * radius, 2 * radius, BURNER_TOP_M + 0.002),
                                fixture.accent, False))
        pieces += [front, _handle(f"{name} oven handle", front, axis, side, fixture.accent)]
    elif fixture.kind in ("fridge", "cabinet"):
        pieces += [front, _handle(f"{name} door handle", front, axis, side, fixture.accent)]
    elif fixture.kind == "shelf":   # open shelving: a dark back and three boards
        back = _front(f"{name} shelf back", along, axis, side, counter_centre, counter_half, below, fixture.accent)
        pieces.append(back)
        for level in range(3):
            z = below[0] + (level + 0.5) * (below[1] - below[0]) / 3
            pieces.append(_front(f"{name} shelf {level + 1}", along, axis, side, counter_centre, counter_half,
                                 (z - 0.01, z + 0.01), fixture.colour, depth=0.06))
    else:                           # cutting board: a darker rim around the board, and a plain cupboard below
        pieces.append(_box(f"{name} board rim", (cx - hx - 0.01, cy - hy - 0.01, -0.002),
                           (cx + hx + 0.01, cy + hy + 0.01, FIXTURE_TOP_M / 2), fixture.accent, collision=False))
        pieces.append(front)
    return pieces


def base_cabinet_pieces(room: Room, counter_centre, counter_half, thickness: float, fronts: list[Piece]) -> list:
    """The floor, the cabinet carcass and plinth under the worktop, and doors along every edge where no
    fixture shows its front."""
    floor_z = -room.worktop_height
    cx, cy = counter_centre
    inner = np.asarray(counter_half) - CARCASS_INSET_M
    pieces = [_box("floor", (cx - 4, cy - 4, floor_z - 0.05), (cx + 4, cy + 4, floor_z), room.floor_colour),
              _box("base cabinets", (cx - inner[0], cy - inner[1], floor_z + PLINTH_M),
                   (cx + inner[0], cy + inner[1], -thickness), room.cabinet_colour),
              _box("plinth", (cx - inner[0] + 0.05, cy - inner[1] + 0.05, floor_z),
                   (cx + inner[0] - 0.05, cy + inner[1] - 0.05, floor_z + PLINTH_M), room.handle_colour)]
    below = (floor_z + PLINTH_M, -thickness - 0.01)
    for axis in (0, 1):
        other = 1 - axis
        span = 2 * inner[other]
        count = max(1, int(round(span / DOOR_WIDTH_M)))
        width = span / count
        start = counter_centre[other] - inner[other]
        for side in (-1, 1):
            for i in range(count):
                along = (start + i * width + 0.004, start + (i + 1) * width - 0.004)
                label = f"door {'xy'[axis]}{'-+'[side > 0]}{i + 1}"
                door = _front(label, along, axis, side, counter_centre, counter_half, below, room.door_colour,
                              depth=0.018)
                if any(_overlaps(door, front) for front in fronts):
                    continue
                pieces += [door, _handle(f"{door.name} handle", door, axis, side, room.handle_colour)]
    return pieces


def _overlaps(a: Piece, b: Piece) -> bool:
    return all(abs(a.centre[i] - b.centre[i]) < (a.size[i] + b.size[i]) / 2 for i in range(3))
