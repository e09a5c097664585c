"""One viewpoint end to end: an object the words call "on the left" is in the left half of the terminal scene
picture and of a headless-Chromium screenshot of meshcat's default (teacher's) view.

Needs Debian's chromium (``apt-get install -y chromium``) and playwright; skipped otherwise.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from bullet_world.viewer.snapshot import find_chromium

pytestmark = [
    pytest.mark.e2e, pytest.mark.browser,
    pytest.mark.skipif(find_chromium() is None,
                       reason="no Chromium at /usr/bin/chromium: install it with apt-get install -y chromium"),
]
pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright; the browser is chromium)")

from bullet_world.viewer.mirror import Viewer  # noqa: E402
from bullet_world.viewer.snapshot import screenshot  # noqa: E402
from dialog.environment import SimulatedKitchen  # noqa: E402
from dialog.language.describe import SceneDescriber  # noqa: E402

MAGENTA, GREY = (1.0, 0.0, 1.0), (0.5, 0.5, 0.5)
WIDTH, HEIGHT = 1000, 700


def magenta(png) -> np.ndarray:
    from PIL import Image

    rgb = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (r > 120) & (b > 120) & (g < 0.35 * r) & (g < 0.35 * b)


@pytest.mark.parametrize("kitchen_name, seed", [("kitchen-1", 3), ("kitchen-3", 3)])
def test_an_object_on_the_left_is_left_in_the_picture_and_in_the_browser(kitchen_name, seed, tmp_path):
    kitchen = SimulatedKitchen(task="pack-lunchbox", kitchen=kitchen_name, seed=seed, pictures=True)
    try:
        scene = kitchen.next_scene(np.random.default_rng(seed))
        describer = SceneDescriber(scene, kitchen.locations, kitchen.viewpoint)
        words = [describer.describe(i) for i in range(scene.n_objects)]
        left = next(i for i, text in enumerate(words) if text.endswith(("on the left", "at the front left",
                                                                         "at the back left")))
        picture = cv2.imread(str(kitchen.scene_picture(scene, tmp_path / "scene.png", highlight=left)))
        column, _ = kitchen._scene_image[2][left]
        assert column < picture.shape[1] / 2, f"{words[left]!r} is drawn in the right half of the scene picture"
        ring = np.all(np.abs(picture.astype(int) - (0, 215, 255)) < 40, axis=2)  # the ring around the object
        assert ring[:, : picture.shape[1] // 2].sum() > 3 * ring[:, picture.shape[1] // 2:].sum()

        target = kitchen.world.object_bodies[left]
        viewer = Viewer(kitchen.world, appearance=lambda body: ("", MAGENTA if body == target else GREY))
        try:
            screenshot(viewer.url, tmp_path / "teacher-view.png", min_drawn=scene.n_objects + 2, width=WIDTH,
                       height=HEIGHT)
        finally:
            viewer.close()
    finally:
        kitchen.close()
    shown = magenta(tmp_path / "teacher-view.png")
    assert shown.sum() > 100, "the object is not in meshcat's default view"
    columns = np.nonzero(shown)[1]
    assert columns.mean() < WIDTH / 2, f"{words[left]!r} shows in the right half of meshcat's default view"
