"""The teacher's numbered scene picture (issue 41): a location's name never covers an object's number, even
when objects stand right where the name would go (the old "cu3board" and "7tove")."""

from __future__ import annotations

import numpy as np

from bullet_world.annotate import boxes_intersect
from dialog.language.pictures import annotate_scene


def test_names_move_off_numbers_that_stand_in_their_corner():
    rgb = np.full((368, 720, 3), 120, dtype=np.uint8)
    regions = {"cupboard": np.array([[300.0, 150.0], [380.0, 150.0], [380.0, 210.0], [300.0, 210.0]]),
               "stove": np.array([[500.0, 60.0], [580.0, 60.0], [580.0, 120.0], [500.0, 120.0]])}
    pixels = [(318.0, 162.0), (340.0, 162.0), (510.0, 72.0), (530.0, 75.0), (560.0, 110.0), (310.0, 200.0)]
    boxes: dict = {}
    annotate_scene(rgb, pixels, [3, 4, 7, 8, 9, 10], highlight=0, regions=regions, boxes=boxes)
    assert len(boxes["numbers"]) == 6 and set(boxes["regions"]) == {"cupboard", "stove"}
    for number in boxes["numbers"]:
        for name in boxes["regions"].values():
            assert not boxes_intersect(number, name)
