""""Show me" answered by clicking the object in the page's 3D view, where meshcat's camera projects it."""

from __future__ import annotations

import time

import numpy as np
import pytest

from bullet_world.viewer.mirror import default_camera
from bullet_world.viewer.snapshot import find_chromium
from dialog.environment import SimulatedKitchen
from dialog.manager import episode_generators
from dialog.transcripts.jsonl import read_session
from tests.e2e.web_helpers import WebCommand, chromium, open_page, wait_for_question

pytestmark = [
    pytest.mark.e2e, pytest.mark.browser,
    pytest.mark.skipif(find_chromium() is None,
                       reason="no Chromium at /usr/bin/chromium: install it with apt-get install -y chromium"),
]
pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright; the browser is chromium)")

FOV_DEGREES = 75.0  # meshcat's default camera
# meshcat's orbit controls turn the camera to the world origin, not to the target set_camera names (its parent's
# origin): a few centimetres apart in the kitchen (bullet_world/viewer/meshcat_objects.py, set_camera)
LOOKED_AT = np.zeros(3)


def project(point, eye, target, width: float, height: float) -> np.ndarray:
    """Pixel (column, row) of a world point in meshcat's view from ``eye`` towards ``target`` (z up)."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    offset = np.asarray(point, dtype=float) - eye
    scale = np.tan(np.radians(FOV_DEGREES) / 2) * (offset @ forward)
    x, y = (offset @ right) / (scale * width / height), (offset @ up) / scale
    return np.array([(x + 1) / 2 * width, (1 - y) / 2 * height])


def test_a_click_on_the_object_in_the_3d_view_shows_it(tmp_path):
    env = SimulatedKitchen(seed=0)
    try:
        scene = env.next_scene(episode_generators(0)["scenes"])
        eye = np.asarray(default_camera(env.world)[0], dtype=float)
        truth = list(scene.truth.concepts)
        centres = np.asarray(scene.truth.positions, dtype=float)
    finally:
        env.close()
    command = WebCommand("teach", "--web", "--strategy", "all-cd", "--seed", "0", "--turns", "2", "--transcript",
                         "runs/t.jsonl", cwd=tmp_path)
    try:
        with chromium() as browser:
            page = open_page(browser, command.url)
            errors: list[str] = []
            page.on("pageerror", lambda error: errors.append(str(error)))
            question = wait_for_question(page)
            assert question["expects"] == "feature"  # all-cd asks which features matter first
            # every frame's start; and the next question comes with something new to draw, as the arm's pose does
            page.evaluate("""() => { window.drawnAt = []; const draw = viewer.renderer.render.bind(viewer.renderer);
                viewer.renderer.render = (scene, camera) => { drawnAt.push(performance.now()); draw(scene, camera); };
                const handled = window.handle;
                window.handle = (message) => {
                    handled(message);
                    if (message.type === "waiting") { viewer.needs_render = true; }
                }; }""")
            page.locator("#features input[data-number='1.1']").check()
            page.get_by_role("button", name="use these").click()
            question = wait_for_question(page, after=question["id"])
            assert question["expects"] == "demo"
            concept = question["text"].split("show me ")[1].split("?")[0].split(" ", 1)[1]
            page.wait_for_function("() => Object.keys(objectNodes).length > 0")
            time.sleep(1.0)  # the 3D view has drawn the scene
            # a frame drawn in software holds the page, so the question is painted first and the view drawn after
            arrived, painted, drawn = page.evaluate("[shownAt, painted === question.id ? paintedAt : null, drawnAt]")
            assert painted is not None and painted >= arrived
            assert not [t for t in drawn if arrived <= t < painted], (arrived, painted, drawn)
            assert [t for t in drawn if t >= painted], "the 3D view was not drawn after the question"
            # headless Chromium draws WebGL in software: the view is drawn with diffuse materials (diffuse.js)
            assert page.evaluate("software3d")
            materials = page.evaluate("""() => { const kinds = new Set();
                viewer.scene.traverse((node) => { if (node.isMesh) { kinds.add(node.material.type); } });
                return [...kinds]; }""")
            assert "MeshLambertMaterial" in materials and "MeshPhongMaterial" not in materials, materials
            box = page.locator("#view3d canvas").bounding_box()
            members = [i for i, name in enumerate(truth) if name == concept]
            nearest = min(members, key=lambda i: np.linalg.norm(centres[i] - eye))  # the least hidden one
            column, row = project(centres[nearest], eye, LOOKED_AT, box["width"], box["height"])
            page.mouse.click(box["x"] + column, box["y"] + row)
            page.wait_for_function("() => ended", timeout=60_000)
            assert not errors, errors
        assert command.finish() == 0
    finally:
        command.stop()
    record = read_session(tmp_path / "runs/t.jsonl")[1][1]
    assert record["answer"]["parsed"] == nearest + 1
    assert record["answer"]["channels"] == ["click"] and record["answer"]["lines"] == [f"number {nearest + 1}"]
