"""The viewer in real headless Chromium: the live page and the exported page show the objects where they are.

Needs Debian's chromium (``apt-get install -y chromium``) and playwright; skipped otherwise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as p
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
from tests.bullet_world.test_viewer import BareWorld  # noqa: E402

WIDTH, HEIGHT, FOV_DEGREES = 1000, 700, 75.0  # meshcat's default camera has a 75 degree vertical field of view
EYE, TARGET = np.array([0.0, 1.0, 0.8]), np.array([0.0, 0.0, 0.05])


def project(point) -> np.ndarray:
    """Pixel (column, row) of a world point seen by meshcat's camera at EYE looking at TARGET, z up."""
    forward = (TARGET - EYE) / np.linalg.norm(TARGET - EYE)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    offset = np.asarray(point, dtype=float) - EYE
    depth = offset @ forward
    scale = np.tan(np.radians(FOV_DEGREES) / 2) * depth
    x, y = (offset @ right) / (scale * WIDTH / HEIGHT), (offset @ up) / scale
    return np.array([(x + 1) / 2 * WIDTH, (1 - y) / 2 * HEIGHT])


def masks(png: Path) -> dict[str, np.ndarray]:
    from PIL import Image

    rgb = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return {"red": (r > 90) & (r > 2.2 * g) & (r > 2.2 * b),
            "green": (g > 70) & (g > 2.0 * r) & (g > 2.0 * b),
            "magenta": (r > 80) & (b > 80) & (r > 2.2 * g) & (b > 2.2 * g),
            "yellow": (r > 150) & (g > 150) & (b < 0.4 * g),
            "orange": (r > 120) & (g > 0.35 * r) & (g < 0.7 * r) & (b < 0.25 * r)}


def centroid(mask: np.ndarray) -> np.ndarray:
    rows, columns = np.nonzero(mask)
    return np.array([columns.mean(), rows.mean()])


def position(world: BareWorld, body: int) -> np.ndarray:
    return np.asarray(p.getBasePositionAndOrientation(body, physicsClientId=world.client)[0])


def test_live_page_shows_each_object_in_its_colour_where_it_stands(tmp_path):
    world = BareWorld()
    bodies = world.three_objects()
    cube, texture = world.textured_cube(tmp_path, (255, 128, 0), (0.05, -0.2, 0.05))  # white, orange texture
    bodies.append(cube)
    centres = [position(world, body) for body in bodies]
    viewer = Viewer(world, camera=(EYE, TARGET), appearance=lambda b: (texture, None) if b == cube else ("", None))
    try:
        shot = screenshot(viewer.url, tmp_path / "live.png", min_drawn=9, width=WIDTH, height=HEIGHT)
    finally:
        viewer.close()
        world.close()
    found = masks(tmp_path / "live.png")
    assert shot["drawn"] >= 9  # the counter, four objects, four numbers
    for colour, centre in zip(("red", "green", "magenta", "orange"), centres):
        assert found[colour].sum() > 300, f"too few {colour} pixels: the object is not drawn"
        assert np.linalg.norm(centroid(found[colour]) - project(centre)) < 45, f"the {colour} object is misplaced"
    assert found["yellow"].sum() < 20, "nothing is highlighted before a question"


def test_exported_page_plays_the_episode_without_a_server(tmp_path):
    world = BareWorld()
    box, _, _ = world.three_objects()
    start = position(world, box)
    viewer = Viewer(world, live=False, record=True, camera=(EYE, TARGET))
    try:
        viewer.on_scene(None)
        viewer.on_question({"kind": "label", "object": 1}, "What is this (object 1)?")
        viewer.update(dwell_s=20.0)  # long enough that a page playing from the start is still before the move
        moved = start + np.array([0.45, -0.25, 0.0])
        p.resetBasePositionAndOrientation(box, moved.tolist(), [0, 0, 0, 1], physicsClientId=world.client)
        viewer.update(dwell_s=1.0)
        page = viewer.export_html(tmp_path / "episode.html")
    finally:
        viewer.close()
        world.close()
    assert viewer.thread.server is None and page["seconds"] >= 3.0
    url = (tmp_path / "episode.html").as_uri()
    screenshot(url, tmp_path / "start.png", min_drawn=7, width=WIDTH, height=HEIGHT, animation_time=0.5)
    screenshot(url, tmp_path / "end.png", min_drawn=7, width=WIDTH, height=HEIGHT, animation_time=page["seconds"])
    screenshot(url, tmp_path / "plain.png", min_drawn=7, width=WIDTH, height=HEIGHT)  # no seeking: as it opens
    first, last, plain = (masks(tmp_path / f"{name}.png") for name in ("start", "end", "plain"))
    assert np.linalg.norm(centroid(first["red"]) - project(start)) < 45
    assert np.linalg.norm(centroid(last["red"]) - project(moved)) < 45
    assert first["yellow"].sum() < 20 < last["yellow"].sum(), "the asked box is highlighted once asked"
    assert last["green"].sum() > 300 and last["magenta"].sum() > 300
    # Issue 23 case 8: the page opens at the episode's end (the last question's highlight, the box moved),
    # not somewhere in its motion.
    assert np.linalg.norm(centroid(plain["red"]) - project(moved)) < 45, "the page does not open at the end"
    assert plain["yellow"].sum() > 20, "the page opens without the last question's highlight"
