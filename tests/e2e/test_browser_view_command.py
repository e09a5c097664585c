"""``teachbot view`` end to end: the kitchen with the Panda pointing, photographed in headless Chromium."""

from __future__ import annotations

import numpy as np
import pytest

from bullet_world.viewer.snapshot import find_chromium

pytestmark = [
    pytest.mark.e2e, pytest.mark.browser,
    pytest.mark.skipif(find_chromium() is None,
                       reason="no Chromium at /usr/bin/chromium: install it with apt-get install -y chromium"),
]
pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright; the browser is chromium)")

from dialog.cli import main  # noqa: E402


def test_view_points_at_an_object_and_photographs_the_pointing_moment(tmp_path, capsys):
    from PIL import Image

    picture, page = tmp_path / "view.png", tmp_path / "view.html"
    code = main(["view", "--seed", "2", "--point", "5", "--screenshot", str(picture), "--export", str(page),
                 "--seconds", "0"])
    out = capsys.readouterr().out
    assert code == 0
    assert "The arm points at object 5" in out and "Viewer:" not in out  # its server is gone when the command ends
    assert f"Page: {page} (" in out and f"open it in a web browser: {page.as_uri()}" in out
    assert page.stat().st_size > 1_000_000  # the Panda's meshes, the objects, the motion
    rgb = np.asarray(Image.open(picture).convert("RGB"), dtype=float)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    asked = (np.abs(r - 255) <= 10) & (np.abs(g - 214) <= 12) & (b <= 25)  # the unlit yellow number of the asked object
    arm = (r > 215) & (g > 215) & (b > 215)                       # the white Panda (and the text panels)
    counter = (np.abs(r - 141) < 30) & (np.abs(g - 115) < 30) & (np.abs(b - 89) < 30) & (r > b + 25)
    assert asked.sum() > 80, "the object asked about is not highlighted"
    assert arm.sum() > 5000, "the arm is missing"
    assert counter.sum() > 50_000, "the counter is missing"
    saturated = (rgb.max(axis=2) - rgb.min(axis=2)) > 90
    assert saturated.sum() > 3000, "the coloured objects are missing"
