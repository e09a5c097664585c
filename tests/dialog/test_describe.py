"""Descriptions from perception: colour names, shape cues, places; numbered pictures."""

import numpy as np
import pytest

from bullet_world.scene import Scene, SceneTruth
from dialog.language.describe import SceneDescriber, colour_name, place_phrase, shape_words
from dialog.language.pictures import annotate_scene, project_points


@pytest.mark.parametrize("rgb, name", [
    ((0.85, 0.12, 0.12), "red"), ((0.95, 0.55, 0.1), "orange"), ((0.95, 0.85, 0.2), "yellow"),
    ((0.3, 0.7, 0.2), "green"), ((0.15, 0.3, 0.75), "blue"), ((0.5, 0.2, 0.7), "purple"),
    ((0.95, 0.95, 0.93), "white"), ((0.5, 0.5, 0.5), "grey"), ((0.05, 0.05, 0.05), "black"),
    ((0.45, 0.28, 0.12), "brown"), ((0.95, 0.7, 0.72), "pink"),
])
def test_colour_names(rgb, name):
    assert colour_name(rgb) == name


def test_shape_cues():
    assert shape_words(0.08, 0.08, 0.08) == ["round"]
    assert shape_words(0.2, 0.08, 0.05) == ["long"]
    assert shape_words(0.16, 0.11, 0.03) == ["flat"]
    assert shape_words(0.07, 0.07, 0.2) == ["round", "tall"]


class Location:
    def __init__(self, centre, half):
        self.centre, self.half_size = centre, half

    def contains(self, xy):
        return all(abs(xy[i] - self.centre[i]) <= self.half_size[i] for i in range(2))


LOCATIONS = {"fridge": Location((-0.4, 0.14, 0), (0.1, 0.1)), "stove": Location((0.4, 0.12, 0), (0.1, 0.1)),
             "counter": Location((0.05, -0.08, 0), (0.14, 0.09))}


def test_places_name_the_nearest_location_but_never_the_counter():
    assert place_phrase((-0.42, 0.15), LOCATIONS) == "at the fridge"
    assert place_phrase((0.22, 0.12), LOCATIONS) == "near the stove"
    assert place_phrase((0.0, -0.05), LOCATIONS) == "in the middle"
    assert place_phrase((-0.2, -0.2), LOCATIONS) == "at the back right"  # seen by the teacher, facing -y


def scene_with(colours, sizes, positions):
    n = len(colours)
    names = ("size.length", "size.width", "size.height")
    truth = SceneTruth(("x",) * n, ("x",) * n, tuple(range(n)), np.zeros((n, 3)), np.zeros((n, 3)))
    return Scene(1, np.array(sizes, dtype=float), names, np.array(positions, dtype=float), np.zeros(n),
                 np.array(colours, dtype=float), truth)


def test_a_described_object_is_the_red_round_thing_near_the_fridge():
    scene = scene_with([(0.8, 0.1, 0.1), (0.2, 0.3, 0.8), (0.9, 0.9, 0.2), (0.3, 0.7, 0.2)],
                       [(0.08, 0.08, 0.08), (0.2, 0.08, 0.05), (0.3, 0.3, 0.3), (0.02, 0.02, 0.02)],
                       [(-0.28, 0.14, 0), (0.4, 0.1, 0), (0.0, 0.0, 0), (0.1, -0.2, 0)])
    describer = SceneDescriber(scene, LOCATIONS)
    assert describer.describe(0) == "the red round thing near the fridge"
    assert describer.describe(1) == "the blue long thing at the stove"
    assert describer.describe(2).startswith("the big yellow")
    table = describer.table_lines()
    assert len(table) == 5 and table[1].split()[:3] == ["1", "red", "8x8x8"]
    assert describer.table_lines([1])[1].split()[0] == "2"


def test_a_scene_without_perception_is_still_described():
    scene = scene_with([(0, 0, 0)], [(0.1, 0.1, 0.1)], [(0, 0, 0)])
    assert SceneDescriber(scene).describe(0) == "the round thing"


def test_projection_and_annotation_mark_the_object():
    view = np.eye(4)
    view[2, 3] = -2.0  # camera 2 m in front, looking down -z
    projection = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, -0.2], [0, 0, -1, 0]], dtype=float)
    pixels = project_points([[0, 0, 0], [1, 0, 0]], view, projection, 200, 100)
    assert pixels[0] == pytest.approx([100, 50]) and pixels[1][0] > 100
    rgb = np.full((100, 200, 3), 120, dtype=np.uint8)
    image = annotate_scene(rgb, pixels, [1, 2], highlight=0)
    assert image.shape == (100, 200, 3) and not np.array_equal(image, rgb[:, :, ::-1])
    ring = image[50, 100 - 31:100 + 32]  # the highlight ring crosses this row
    assert (ring[:, 1] > 180).any()


def test_objects_that_read_alike_get_their_size_or_their_number(tmp_path):
    """Issue 42, case 7: two objects of one scene were both "the blue round tall thing at the back left"."""
    blue, spot = (0.15, 0.3, 0.75), (-0.3, 0.3, 0)
    red, green = (0.8, 0.1, 0.1), (0.3, 0.7, 0.2)
    scene = scene_with([blue, blue, blue, red, red, green, green],
                       [(0.06, 0.06, 0.14), (0.07, 0.07, 0.16), (0.07, 0.07, 0.16), (0.3, 0.1, 0.05),
                        (0.3, 0.12, 0.05), (0.02, 0.02, 0.02), (0.02, 0.03, 0.02)],
                       [spot, spot, spot, (0.4, 0.1, 0), (0.1, -0.2, 0), (0.0, 0.0, 0), (-0.28, 0.14, 0)])
    describer = SceneDescriber(scene, LOCATIONS)
    alone = describer.describe(0, distinct=False)
    assert alone == describer.describe(1, distinct=False) == describer.describe(2, distinct=False)
    assert describer.describe(0) == f"{alone}, 6x6x14 cm"  # its size tells it apart
    assert describer.describe(1) == f"{alone} (number 2)" and describer.describe(2) == f"{alone} (number 3)"
    assert describer.describe(3) == describer.describe(3, distinct=False)  # one of a kind: unchanged
    descriptions = [describer.describe(i) for i in range(7)]
    assert len(set(descriptions)) == 7


def test_every_object_of_the_demo_scenes_is_described_distinctly():
    from dialog.environment import SimulatedKitchen

    kitchen = SimulatedKitchen(task="pack-lunchbox", kitchen="kitchen-1", seed=0)
    try:
        rng = np.random.default_rng(0)
        for _ in range(6):
            scene = kitchen.next_scene(rng)
            describer = SceneDescriber(scene, kitchen.locations, kitchen.viewpoint)
            texts = [describer.describe(i) for i in range(scene.n_objects)]
            assert len(set(texts)) == len(texts), texts
    finally:
        kitchen.close()
