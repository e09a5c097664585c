"""The 3D view's number and location labels are readable at the page's size (issue 50, item 4): drawn alone on a
white ground and measured in the view's pixels, a label's digits stand about as tall as the page's own digits."""

from __future__ import annotations

import base64
import io
import time

import numpy as np
import pytest
from PIL import Image

from bullet_world.viewer.meshcat_objects import TEXT_STYLES, text_image
from bullet_world.viewer.snapshot import find_chromium
from tests.e2e.web_helpers import WebCommand, chromium, open_page, wait_for_question

pytestmark = [
    pytest.mark.e2e, pytest.mark.browser,
    pytest.mark.skipif(find_chromium() is None,
                       reason="no Chromium at /usr/bin/chromium: install it with apt-get install -y chromium"),
]
pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright; the browser is chromium)")
ndimage = pytest.importorskip("scipy.ndimage")

DRAW_ONLY = """(branch) => {
    // draw the sprites under the node named ``branch`` alone, on white, and return the frame as a PNG
    const hidden = [];
    viewer.scene.traverse((node) => {
        let inBranch = false;
        for (let up = node; up; up = up.parent) { if (up.name === branch) { inBranch = true; } }
        if (node.isMesh || node.isLine || node.isPoints || (node.isSprite && !inBranch)) {
            if (node.visible) { hidden.push(node); node.visible = false; }
        }
    });
    const background = viewer.scene.background;
    viewer.scene.background = new MeshCat.THREE.Color(0xffffff);
    viewer.renderer.setClearColor(0xffffff, 1);
    viewer.renderer.render(viewer.scene, viewer.camera);
    const png = viewer.renderer.domElement.toDataURL("image/png");
    hidden.forEach((node) => { node.visible = true; });
    viewer.scene.background = background;
    return png;
}"""
PAGE_INK = """(text) => {
    // how tall ``text`` stands in the page's own font, in CSS pixels (its ink, not its line)
    const context = document.createElement("canvas").getContext("2d");
    context.font = getComputedStyle(document.body).font;
    const metrics = context.measureText(text);
    return metrics.actualBoundingBoxAscent + metrics.actualBoundingBoxDescent;
}"""


def panel_heights(png: str) -> list[int]:
    """The pixel height of each label in a frame of sprites on white: its panel where the panel shows (a number
    label's dark one), else its letters (a location label's panel is white and see-through)."""
    image = np.asarray(Image.open(io.BytesIO(base64.b64decode(png.split(",", 1)[1]))).convert("RGB"), dtype=int)
    ink = np.abs(image - 255).sum(axis=2) > 30
    labels, count = ndimage.label(ndimage.binary_closing(ink, iterations=2))
    boxes = ndimage.find_objects(labels)
    return [box[0].stop - box[0].start for box in boxes if (box[1].stop - box[1].start) >= 6]


def digit_share(text: str, style: str) -> float:
    """The share of a label panel's height its digits take (as meshcat_objects.text_image draws it)."""
    from bullet_world.viewer.meshcat_objects import _font

    font = _font(TEXT_STYLES[style][2])
    _, top, _, bottom = font.getbbox(text)
    data, _ = text_image(text, style)
    return (bottom - top) / Image.open(io.BytesIO(data)).height


def test_the_3d_labels_are_about_as_tall_as_the_pages_text(tmp_path):
    command = WebCommand("teach", "--web", "--strategy", "active", "--seed", "0", "--turns", "1", "--transcript",
                         "runs/t.jsonl", cwd=tmp_path)
    try:
        with chromium() as browser:
            page = open_page(browser, command.url)
            wait_for_question(page)
            page.wait_for_function("() => viewer && Object.keys(objectNodes).length > 0")
            time.sleep(1.0)  # the 3D view has its scene
            ratio = page.evaluate("() => viewer.renderer.domElement.width / viewer.renderer.domElement.clientWidth")
            numbers = [h / ratio for h in panel_heights(page.evaluate(DRAW_ONLY, "labels"))]
            places = [h / ratio for h in panel_heights(page.evaluate(DRAW_ONLY, "location-names"))]
            digit, word = page.evaluate(PAGE_INK, "8"), page.evaluate(PAGE_INK, "dg")
    finally:
        command.stop()
    assert len(numbers) >= 3 and places, (numbers, places)
    number_digits = float(np.median(numbers)) * digit_share("8", "label")
    place_letters = float(np.median(places))  # from the top of a 'd' to the foot of a 'g', as ``word``
    # readable beside the page's text: no smaller than 90 % of it, and not a shout
    print(f"3D labels: number digits {number_digits:.1f} px, page digits {digit:.1f} px; place words "
          f"{float(np.median(places)):.1f} px, page words {word:.1f} px")
    assert 0.9 * digit <= number_digits <= 2.5 * digit, (number_digits, digit, numbers)
    assert 0.9 * word <= place_letters <= 2.5 * word, (place_letters, word, places)
