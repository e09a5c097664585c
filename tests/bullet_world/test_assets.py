"""Generated assets: unit meshes that fill the unit cube, textures whose detail differs by pattern."""

import cv2
import numpy as np
import pytest

from bullet_world.catalogue import load_task
from bullet_world.meshes import build_mesh, mesh_file, mesh_parameters, true_size
from bullet_world.textures import texture_file, texture_image


def test_every_catalogue_mesh_fills_the_unit_cube():
    for task in ("pack-lunchbox", "prepare-lunch", "sort-groceries"):
        for kind in load_task(task).kinds:
            for look in kind.states:
                text = build_mesh(mesh_parameters(look)).obj_text()
                vertices = np.array([[float(v) for v in line.split()[1:]] for line in text.splitlines()
                                     if line.startswith("v ")])
                assert vertices.min(axis=0) == pytest.approx([-0.5] * 3, abs=1e-4), (kind.name, look.name)
                assert vertices.max(axis=0) == pytest.approx([0.5] * 3, abs=1e-4), (kind.name, look.name)


def test_sizes_follow_the_shape():
    kinds = {k.name: k for k in load_task("pack-lunchbox").kinds}
    assert true_size(kinds["orange"].states[0], {"radius": 0.04}) == pytest.approx((0.08, 0.08, 0.08))
    assert true_size(kinds["soda-can"].states[0], {"radius": 0.03, "height": 0.12}) == pytest.approx((0.06, 0.06,
                                                                                                       0.12))
    apple = next(k for k in load_task("prepare-lunch").kinds if k.name == "apple").states[1]
    length, width, height = true_size(apple, {"radius": 0.04, "height": 0.01})
    assert length > width == pytest.approx(0.08) and height == pytest.approx(0.02)


def test_files_are_written_once_into_the_cache(tmp_path):
    look = load_task("pack-lunchbox").kinds[0].states[0]
    first = mesh_file(look, tmp_path)
    assert first == mesh_file(look, tmp_path) and first.endswith(".obj")
    png = texture_file("print", (0.8, 0.2, 0.2), (1, 1, 1), 3, tmp_path)
    assert cv2.imread(png).shape == (128, 256, 3)


def orb_count(image: np.ndarray) -> int:
    detector = cv2.ORB_create(nfeatures=5000, edgeThreshold=7, patchSize=7, fastThreshold=14)
    return len(detector.detect(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY), None))


def test_textures_are_reproducible_and_differ_in_detail():
    colour = (0.8, 0.6, 0.2)
    assert np.array_equal(texture_image("crinkle", colour, colour, 5), texture_image("crinkle", colour, colour, 5))
    counts = {p: orb_count(texture_image(p, colour, (0.9, 0.8, 0.5), 5)) for p in
              ("plain", "speckle", "label", "print", "crinkle")}
    assert counts["plain"] < counts["label"] < counts["print"]
    assert counts["crinkle"] > 3 * counts["speckle"]
