"""Non-overlapping placement of object footprints on the counter, within the arm's reach.

Footprints are rectangles (boxes, bags, slices) or circles (cans, fruit,
bowls). Two footprints keep at least the kitchen's gap between them, tested
with separating axes (the axes of both rectangles and the line between the
centres), which is exact for circles and never lets shapes overlap. Objects
are placed largest first; an object whose state names a semantic location is
placed inside that location's region.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from bullet_world.kitchen import Kitchen, Location
from learning.errors import SceneError


class PlacementError(SceneError):
    """The objects do not fit the kitchen's object region (or their locations) without overlap."""

BATCH = 64        # candidate poses tried at once for one object (more in later batches)
BATCHES = 10      # batches per object before the whole scene starts again
ATTEMPTS = 25     # whole-scene attempts before giving up
SPILL_M = 0.05    # when a location is full, objects that belong there may stand this much outside it


@dataclass(frozen=True)
class Footprint:
    """An outline on the counter: a rectangle (half sizes) or a circle (radius)."""

    shape: str       # "rect" or "circle"
    half_length: float
    half_width: float

    @classmethod
    def from_tuple(cls, outline: tuple[str, float, float]) -> Footprint:
        shape, a, b = outline
        return cls("rect", a / 2, b / 2) if shape == "rect" else cls("circle", a, a)

    @property
    def radius(self) -> float:
        """Radius of the circle that holds the footprint."""
        return float(np.hypot(self.half_length, self.half_width)) if self.shape == "rect" else self.half_length

    @property
    def area(self) -> float:
        return 4 * self.half_length * self.half_width if self.shape == "rect" else np.pi * self.half_length ** 2


def _shape_rows(footprints: list[Footprint], centres: np.ndarray, yaws: np.ndarray) -> np.ndarray:
    """(n, 6) rows: centre x, y, yaw, half length, half width, rounding radius."""
    sizes = np.array([(fp.half_length, fp.half_width, 0.0) if fp.shape == "rect" else (0.0, 0.0, fp.half_length)
                      for fp in footprints]).reshape(-1, 3)
    return np.column_stack([np.asarray(centres).reshape(-1, 2), np.asarray(yaws).reshape(-1), sizes])


def _rows_for(fp: Footprint, centres: np.ndarray, yaws: np.ndarray) -> np.ndarray:
    """Rows of 6 for many poses of one footprint."""
    size = (fp.half_length, fp.half_width, 0.0) if fp.shape == "rect" else (0.0, 0.0, fp.half_length)
    return np.column_stack([centres, yaws, np.tile(size, (len(yaws), 1))])


def _gap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Lower bound on the distance between footprints ``a`` and ``b`` (broadcastable rows of 6)."""
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    distance = np.hypot(dx, dy)
    apart = distance > 1e-12  # coincident centres: any direction will do as the centre axis
    centre_axis = (np.where(apart, dx / np.where(apart, distance, 1.0), 1.0),
                   np.where(apart, dy / np.where(apart, distance, 1.0), 0.0))
    trig = [(np.cos(shape[..., 2]), np.sin(shape[..., 2])) for shape in (a, b)]
    axes = [centre_axis] + [axis for c, s in trig for axis in ((c, s), (-s, c))]
    best = np.full(distance.shape, -np.inf)
    for ax, ay in axes:
        extents = 0.0
        for shape, (c, s) in zip((a, b), trig):
            extents = extents + shape[..., 3] * np.abs(c * ax + s * ay) + shape[..., 4] * np.abs(c * ay - s * ax) \
                + shape[..., 5]
        best = np.maximum(best, np.abs(dx * ax + dy * ay) - extents)
    return best


def separation(candidates: np.ndarray, placed: np.ndarray) -> np.ndarray:
    """(k, m) lower bound on the gap between each candidate and each placed footprint (rows of 6)."""
    return _gap(candidates[:, None, :], placed[None, :, :])


def _bounding_radius(rows: np.ndarray) -> np.ndarray:
    return np.hypot(rows[:, 3], rows[:, 4]) + rows[:, 5]


def _clear(candidates: np.ndarray, placed: np.ndarray, gap: float) -> np.ndarray:
    """Which candidates keep ``gap`` from every placed footprint: bounding circles first, separating
    axes only for the pairs whose circles come close."""
    ok = np.ones(len(candidates), dtype=bool)
    if len(placed) == 0:
        return ok
    reach = _bounding_radius(candidates)[:, None] + _bounding_radius(placed)[None, :] + gap
    distance = np.hypot(candidates[:, None, 0] - placed[None, :, 0], candidates[:, None, 1] - placed[None, :, 1])
    first, second = np.nonzero(distance < reach)
    if len(first):
        too_close = _gap(candidates[first], placed[second]) < gap
        ok[first[too_close]] = False
    return ok


POOL_SIZE = 40000  # candidate spots drawn once per kitchen region
_POOLS: dict[tuple, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _region_pool(kitchen: Kitchen) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Spots inside the kitchen's object region (fixed seed), their distance to the counter edge, and the
    cumulative probability of drawing each (half uniform, half gathered around the focus)."""
    key = (kitchen.name, kitchen.region_x, kitchen.region_y, kitchen.min_reach, kitchen.max_reach,
           kitchen.max_bearing, kitchen.focus, kitchen.focus_spread, kitchen.robot_base, kitchen.robot_yaw)
    if key not in _POOLS:
        rng = np.random.default_rng(20240611)
        low = np.array([kitchen.region_x[0], kitchen.region_y[0]])
        high = np.array([kitchen.region_x[1], kitchen.region_y[1]])
        spots = rng.uniform(low, high, (POOL_SIZE * 4, 2))
        spots = spots[kitchen.in_object_region(spots)][:POOL_SIZE]
        if len(spots) == 0:
            raise PlacementError(f"kitchen '{kitchen.name}': the [object_region] holds no spot within reach")
        weights = np.full(len(spots), 1.0 / len(spots))
        if kitchen.focus is not None:
            gathered = np.exp(-0.5 * np.sum((spots - kitchen.focus) ** 2, axis=1) / kitchen.focus_spread ** 2)
            weights = 0.5 * weights + 0.5 * gathered / gathered.sum()
        _POOLS[key] = (spots, kitchen.counter_edge_distance(spots), np.cumsum(weights) / weights.sum())
    return _POOLS[key]


def _outside(xy: np.ndarray, radius: float, regions: list[Location]) -> np.ndarray:
    """Which centres keep a footprint of ``radius`` clear of every region rectangle."""
    keep = np.ones(len(xy), dtype=bool)
    for region in regions:
        gap = np.maximum(np.abs(xy - np.asarray(region.centre[:2])) - np.asarray(region.half_size), 0.0)
        keep &= np.hypot(gap[:, 0], gap[:, 1]) > radius
    return keep


def _candidates(fp: Footprint, kitchen: Kitchen, location: Location | None, rng: np.random.Generator,
                avoid: list[Location] = (), count: int = BATCH):
    margin = fp.radius
    if location is None:
        spots, edge, cumulative = _region_pool(kitchen)
        pick = np.minimum(np.searchsorted(cumulative, rng.random(count)), len(spots) - 1)
        xy, keep = spots[pick], edge[pick] >= margin
        keep &= (xy[:, 0] >= kitchen.region_x[0] + margin) & (xy[:, 0] <= kitchen.region_x[1] - margin)
        keep &= (xy[:, 1] >= kitchen.region_y[0] + margin) & (xy[:, 1] <= kitchen.region_y[1] - margin)
        if avoid:  # keep clear of reserved locations and the spill-over strip around them
            keep &= _outside(xy, margin + SPILL_M, avoid)
    else:
        low = np.asarray(location.centre[:2]) - location.half_size
        xy = rng.uniform(low, low + 2 * np.asarray(location.half_size), (count, 2))
        distance = np.hypot(*kitchen.robot_frame(xy).T)
        keep = (distance <= kitchen.max_reach) & (distance >= kitchen.min_reach)
        keep &= kitchen.counter_edge_distance(xy) >= margin
    yaw = rng.uniform(0.0, np.pi, count)
    return xy[keep], yaw[keep]


def place(footprints: list[Footprint], kitchen: Kitchen, rng: np.random.Generator,
          locations: list[Location | None] | None = None, fixed: np.ndarray | None = None,
          gap: float | None = None, avoid: list[Location] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Centres (n, 2) and yaws (n,) for ``footprints`` that overlap neither each other nor the
    ``fixed`` footprints (rows of 6, see :func:`separation`). An object with a location stands with its
    centre in that location; the others keep clear of the ``avoid`` regions. Raises RuntimeError when
    they do not fit."""
    n = len(footprints)
    locations = locations or [None] * n
    gap = kitchen.min_gap if gap is None else gap
    fixed = np.zeros((0, 6)) if fixed is None else np.asarray(fixed, dtype=float).reshape(-1, 6)
    # constrained objects first (less room), then by size
    order = sorted(range(n), key=lambda i: (locations[i] is None, -footprints[i].area))
    for _ in range(ATTEMPTS):
        centres, yaws = np.zeros((n, 2)), np.zeros(n)
        placed_rows = [fixed]
        done = 0
        for index in order:
            fp = footprints[index]
            for batch in range(BATCHES):
                location = locations[index]
                if location is not None and batch >= BATCHES // 2:  # a full location: stand next to it
                    location = replace(location, half_size=tuple(h + SPILL_M for h in location.half_size))
                xy, yaw = _candidates(fp, kitchen, location, rng, avoid, BATCH * (1 + batch // 2))
                if len(xy) == 0:
                    continue
                rows = _rows_for(fp, xy, yaw)
                ok = _clear(rows, np.vstack(placed_rows), gap)
                if ok.any():
                    first = int(np.argmax(ok))
                    centres[index], yaws[index] = xy[first], yaw[first]
                    placed_rows.append(rows[first:first + 1])
                    done += 1
                    break
            else:
                break
        if done == n:
            return centres, yaws
    area = sum(fp.area for fp in footprints)
    raise PlacementError(f"cannot place {n} objects ({area:.2f} m^2 of footprint) in kitchen '{kitchen.name}' "
                         f"without overlap; use fewer objects or a kitchen with a larger [object_region]")


def footprint_rows(footprints: list[Footprint], centres: np.ndarray, yaws: np.ndarray) -> np.ndarray:
    """Rows of 6 for footprints already on the counter (to keep clear of them)."""
    return _shape_rows(footprints, np.asarray(centres).reshape(-1, 2), np.asarray(yaws).reshape(-1))
