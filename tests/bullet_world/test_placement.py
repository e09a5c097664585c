"""Placement: footprints never overlap, stay within reach, and respect semantic locations."""

import numpy as np
import pytest

from bullet_world.kitchen import load_kitchen
from bullet_world.placement import Footprint, footprint_rows, place, separation


def test_separation_is_exact_for_circles_and_safe_for_rectangles():
    circles = footprint_rows([Footprint("circle", 0.05, 0.05)] * 2, [[0, 0], [0.13, 0]], [0, 0])
    assert separation(circles[:1], circles[1:])[0, 0] == pytest.approx(0.03)
    boxes = footprint_rows([Footprint("rect", 0.1, 0.02)] * 2, [[0, 0], [0.0, 0.1]], [0.0, 0.0])
    assert separation(boxes[:1], boxes[1:])[0, 0] == pytest.approx(0.06)
    crossing = footprint_rows([Footprint("rect", 0.1, 0.01)] * 2, [[0, 0], [0, 0]], [0.0, np.pi / 2])
    assert separation(crossing[:1], crossing[1:])[0, 0] < 0


def test_placed_footprints_keep_the_gap_and_stay_in_the_region():
    kitchen = load_kitchen("kitchen-1")
    rng = np.random.default_rng(0)
    footprints = [Footprint("rect", 0.08, 0.03)] * 15 + [Footprint("circle", 0.04, 0.04)] * 15
    centres, yaws = place(footprints, kitchen, rng)
    rows = footprint_rows(footprints, centres, yaws)
    gaps = separation(rows, rows) + np.eye(len(rows)) * 9
    assert gaps.min() >= kitchen.min_gap - 1e-9
    assert np.all(kitchen.in_object_region(centres))


def test_objects_with_a_location_stand_there_and_others_keep_clear():
    kitchen = load_kitchen("kitchen-2")
    stove = kitchen.locations["stove"]
    footprints = [Footprint("circle", 0.05, 0.05)] * 2 + [Footprint("rect", 0.06, 0.03)] * 12
    locations = [stove, stove] + [None] * 12
    centres, _ = place(footprints, kitchen, np.random.default_rng(3), locations, avoid=[stove])
    assert all(stove.contains(c) for c in centres[:2])
    offsets = np.abs(centres[2:] - np.asarray(stove.centre[:2])) - np.asarray(stove.half_size)
    assert np.all(np.hypot(*np.maximum(offsets, 0).T) > 0.06)


def test_too_many_objects_is_a_clear_error():
    kitchen = load_kitchen("kitchen-1")
    with pytest.raises(RuntimeError, match="cannot place 200 objects .* without overlap"):
        place([Footprint("rect", 0.1, 0.05)] * 200, kitchen, np.random.default_rng(0))
