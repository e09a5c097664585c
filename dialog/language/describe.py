"""Plain-language descriptions of scene objects: "the red round thing near the fridge, number 4".

Everything here comes from what the robot perceived (mean colour, measured
size, perceived position) and the kitchen's semantic locations, never from the
hidden ground truth.
"""

from __future__ import annotations

import colorsys
from functools import lru_cache
from pathlib import Path

import numpy as np

from bullet_world.viewpoint import Viewpoint
from learning.datafiles import check_keys, number, read_toml, tables, text
from learning.errors import DataFileError

COLOURS_FILE = Path(__file__).parents[1] / "data" / "colours.toml"
SIZE_FEATURES = {"length": ("size.length", "bbox.length", "length"), "width": ("size.width", "bbox.width", "width"),
                 "height": ("size.height", "bbox.height", "height")}
ROUND_ASPECT = 1.2      # length / width at most this: round (or square) from above
LONG_ASPECT = 1.7       # at least this: long
FLAT_RATIO = 0.45       # height / width at most this: flat
TALL_RATIO = 1.4        # height / length at least this: tall
NEAR_METRES = 0.2       # farther from every location: the area of the counter ("at the front left")
SIDE_METRES = 0.12      # this far to the teacher's left or right of the work area's middle: "left", "right"
DEPTH_METRES = 0.10     # this far towards the teacher (front) or the robot (back)
SURFACES = ("counter", "table", "worktop")
# Transcripts written before the teacher's viewpoint used fixed world sides (front: y < -0.08, left: x < -0.12):
# the same words from a viewer facing +y, whose middle is y = 0.02. Replays accept them.
OLD_WORLD_VIEWPOINT = Viewpoint(facing=(0.0, 1.0), centre=(0.0, 0.02))


@lru_cache(maxsize=2)
def colour_table(path: str | Path = COLOURS_FILE) -> dict:
    table = read_toml(path, "colour table")
    where = str(path)
    check_keys(table, where, required=("grey_saturation", "grey", "hue"))
    number(table, "grey_saturation", where, low=0.0, high=1.0)
    for index, grey in enumerate(tables(table, "grey", where, nonempty=True)):
        here = f"{where} grey {index + 1}"
        check_keys(grey, here, required=("name", "below_value"))
        text(grey, "name", here)
        number(grey, "below_value", here, low=0.0)
    for index, band in enumerate(tables(table, "hue", where, nonempty=True)):
        here = f"{where} hue {index + 1}"
        check_keys(band, here, required=("name", "from", "to"),
                   optional=("pale_name", "pale_saturation", "dark_name", "dark_value"))
        text(band, "name", here)
        start = number(band, "from", here, low=0.0, high=360.0)
        number(band, "to", here, above=start, high=360.0)
        for name_key, limit_key in (("pale_name", "pale_saturation"), ("dark_name", "dark_value")):
            if (name_key in band) != (limit_key in band):
                raise DataFileError(f"{here}: '{name_key}' and '{limit_key}' go together; give both or neither")
            if name_key in band:
                text(band, name_key, here)
                number(band, limit_key, here, low=0.0, high=1.0)
    return table


def colour_name(rgb) -> str:
    """A colour word for a perceived mean colour (RGB in 0..1), by hue bands in ``colours.toml``."""
    red, green, blue = (float(np.clip(c, 0.0, 1.0)) for c in rgb)
    hue, saturation, value = colorsys.rgb_to_hsv(red, green, blue)
    hue *= 360.0
    table = colour_table()
    if saturation < table["grey_saturation"] or value < 0.12:
        for grey in table["grey"]:
            if value < grey["below_value"]:
                return grey["name"]
        return table["grey"][-1]["name"]
    for band in table["hue"]:
        if band["from"] <= hue < band["to"] or (hue == 360.0 and band["to"] == 360.0):
            if "dark_name" in band and value < band["dark_value"]:
                return band["dark_name"]
            if "pale_name" in band and saturation < band["pale_saturation"]:
                return band["pale_name"]
            return band["name"]
    return "coloured"


def shape_words(length: float, width: float, height: float) -> list[str]:
    """Shape cues from the measured size: round, long, flat, tall."""
    long_side, short_side = max(length, width), max(min(length, width), 1e-6)
    cues = []
    aspect = long_side / short_side
    if aspect <= ROUND_ASPECT:
        cues.append("round" if abs(length - width) / long_side < 0.12 else "squarish")
    elif aspect >= LONG_ASPECT:
        cues.append("long")
    if height / short_side <= FLAT_RATIO:
        cues.append("flat")
    elif height / long_side >= TALL_RATIO:
        cues.append("tall")
    return cues


def area_phrase(xy, viewpoint: Viewpoint | None = None) -> str:
    """Where on the counter, as the teacher across the counter sees it: front is the teacher's side, back the
    robot's, left the teacher's left (see :mod:`bullet_world.viewpoint`)."""
    right, towards_teacher = (viewpoint or Viewpoint()).sides(xy)[0]
    depth = "front" if towards_teacher > DEPTH_METRES else "back" if towards_teacher < -DEPTH_METRES else "middle"
    side = "right" if right > SIDE_METRES else "left" if right < -SIDE_METRES else ""
    if depth == "middle":
        return f"on the {side}" if side else "in the middle"
    return f"at the {depth} {side}".rstrip() if side else f"at the {depth}"


def place_phrase(xy, locations: dict, viewpoint: Viewpoint | None = None) -> str:
    """"at the stove" inside a location's region, "near the fridge" close to one, else the area of the counter
    seen from ``viewpoint`` (the teacher's; a teacher at +y facing -y when not given).

    Work surfaces (the counter itself) hold everything, so they name no place.
    """
    xy = np.asarray(xy, dtype=float)[:2]
    places = {name: loc for name, loc in (locations or {}).items() if name not in SURFACES}
    for name, location in places.items():
        contains = getattr(location, "contains", None)
        if contains is not None and contains(xy):
            return f"at the {name}"
    if places:
        centres = {name: np.asarray(getattr(loc, "centre", loc), dtype=float)[:2] for name, loc in places.items()}
        name, distance = min(((n, float(np.linalg.norm(xy - c))) for n, c in centres.items()), key=lambda p: p[1])
        if distance <= NEAR_METRES:
            return f"near the {name}"
    return area_phrase(xy, viewpoint)


def _column(scene, candidates) -> np.ndarray | None:
    for name in candidates:
        if name in scene.feature_names:
            return scene.feature(name)
    return None


class SceneDescriber:
    """Descriptions and a short table of one scene's objects, numbered from 1."""

    def __init__(self, scene, locations: dict | None = None, viewpoint: Viewpoint | None = None):
        self.scene = scene
        self.locations = locations or {}
        self.viewpoint = viewpoint or Viewpoint()
        n = scene.n_objects
        sizes = [_column(scene, SIZE_FEATURES[k]) for k in ("length", "width", "height")]
        self.sizes = np.column_stack(sizes) if all(s is not None for s in sizes) else None
        self.colours = np.asarray(scene.colours, dtype=float).reshape(n, -1) if n else np.zeros((0, 3))
        has_colour = self.colours.shape[1] == 3 and np.any(self.colours > 0)
        self.colour_names = [colour_name(c) if has_colour else "" for c in self.colours]
        positions = np.asarray(scene.positions, dtype=float).reshape(n, -1) if n else np.zeros((0, 3))
        placed = positions.shape[1] >= 2 and bool(np.any(positions[:, :2] != 0))
        self.places = [place_phrase(p, self.locations, self.viewpoint) if placed else "" for p in positions]
        volumes = np.prod(self.sizes, axis=1) if self.sizes is not None else np.zeros(0)
        if n >= 3 and len(volumes) and np.ptp(volumes) > 0:  # small and big only compared with the rest
            low, high = np.quantile(volumes, [0.25, 0.75])
            self.size_words = ["small" if v <= low else "big" if v >= high else "" for v in volumes]
        else:
            self.size_words = [""] * n

    def describe(self, index: int, distinct: bool = True) -> str:
        """"the big red round thing near the fridge" (as much as the robot perceives); when another object of the
        scene reads the same, its size in centimetres is added (and, should that tie too, its number), so no
        two objects of a scene share a description. ``distinct=False``: the words alone (as before issue 42)."""
        text = self._words(index)
        if not distinct:
            return text
        if getattr(self, "_all_words", None) is None:
            self._all_words = [self._words(other) for other in range(self.scene.n_objects)]
        alike = [other for other, words in enumerate(self._all_words) if words == text]
        if len(alike) < 2:
            return text
        sized = self._with_size(index)
        if self.sizes is not None and sum(self._with_size(other) == sized for other in alike) == 1:
            return sized
        return f"{text} (number {index + 1})"

    def _with_size(self, index: int) -> str:
        if self.sizes is None:
            return self._words(index)
        return f"{self._words(index)}, {'x'.join(f'{v * 100:.0f}' for v in self.sizes[index])} cm"

    def _words(self, index: int) -> str:
        words = [self.size_words[index], self.colour_names[index]]
        if self.sizes is not None:
            words += shape_words(*self.sizes[index])
        words = [w for w in words if w]
        text = "the " + " ".join([*words, "thing"]) if words else "the object"
        if self.places[index]:
            text += " " + self.places[index]
        return text

    def table_lines(self, only=None) -> list[str]:
        """A short table: number, colour, size in centimetres, place (all objects, or the indices ``only``)."""
        header = f"{'no.':>3}  {'colour':<11} {'size (cm)':<15} place"
        lines = [header]
        for index in (range(self.scene.n_objects) if only is None else only):
            size = ("x".join(f"{v * 100:.0f}" for v in self.sizes[index]) if self.sizes is not None else "?")
            if self.size_words[index]:
                size = f"{size} {self.size_words[index]}"
            lines.append(f"{index + 1:>3}  {self.colour_names[index] or '?':<11} {size:<15} "
                         f"{self.places[index] or '?'}")
        return lines
