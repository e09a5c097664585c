"""``--viewer`` on demo, teach and recipe: a real meshcat server on 127.0.0.1 that leaves the results unchanged."""

from __future__ import annotations

import json
import urllib.request
from pathlib import Path

import pytest

from bullet_world.viewer import thread as viewer_thread
from bullet_world.viewer.server import ViewerError
from dialog import viewer as viewer_options
from dialog.cli import main

pytestmark = pytest.mark.e2e


@pytest.fixture
def served_pages(monkeypatch):
    """Wrap the real viewer start: fetch the page while the session runs, keep (url, HTTP status, viewer)."""
    pages = []
    real_start = viewer_options.start_viewer

    def start_and_fetch(args, world):
        viewer = real_start(args, world)
        if viewer is not None and viewer.url:
            with urllib.request.urlopen(viewer.url, timeout=10) as response:
                pages.append((viewer.url, response.status, viewer))
        return viewer

    monkeypatch.setattr(viewer_options, "start_viewer", start_and_fetch)
    for module in ("dialog.commands.teach", "dialog.commands.recipe"):  # imported by name there
        monkeypatch.setattr(f"{module}.start_viewer", start_and_fetch)
    return pages


def last_json(out: str) -> dict:
    return json.loads(out.strip().splitlines()[-1])


def without_timing(summary: dict, *keys: str) -> dict:
    return {key: value for key, value in summary.items() if key not in ("seconds", *keys)}


def test_demo_with_a_live_viewer_prints_its_url_and_gives_the_same_episode(tmp_path, capsys, served_pages):
    common = ["demo", "--seed", "5", "--turns", "6", "--budget", "8", "--change-every", "3", "--json"]
    assert main([*common, "--transcript", str(tmp_path / "plain.jsonl")]) == 0
    plain = capsys.readouterr()
    assert "Viewer:" not in plain.err and not served_pages
    assert main([*common, "--transcript", str(tmp_path / "viewed.jsonl"), "--viewer"]) == 0
    viewed = capsys.readouterr()
    ((url, status, viewer),) = served_pages
    assert url.startswith("http://127.0.0.1:") and status == 200
    assert f"Viewer: {url}" in viewed.err.splitlines()
    assert viewer.thread.server is None  # closed with the session
    assert without_timing(last_json(viewed.out), "transcript") == without_timing(last_json(plain.out), "transcript")
    assert (tmp_path / "viewed.jsonl").read_bytes() == (tmp_path / "plain.jsonl").read_bytes()


def test_recipe_with_a_live_viewer_shows_captions_and_gives_the_same_result(capsys, served_pages):
    common = ["recipe", "--recipe", "serve-salad", "--kitchen", "1", "--demos", "2", "--execute", "--json",
              "--seed", "3"]
    assert main(common) == 0
    plain = capsys.readouterr()
    assert main([*common, "--viewer"]) == 0
    viewed = capsys.readouterr()
    ((url, status, viewer),) = served_pages
    assert url.startswith("http://127.0.0.1:") and status == 200 and f"Viewer: {url}" in viewed.err
    assert viewer.thread.server is None
    summary = last_json(viewed.out)
    assert without_timing(summary) == without_timing(last_json(plain.out))
    assert len(summary["steps"]) == 2
    # the last caption is the run's outcome, in the viewer's own text fields
    done = sum(step["status"] == "done" and step["correct_object"] and step["in_true_end_region"]
               for step in summary["steps"])
    assert viewer.question == "Robot: serve-salad done"
    assert viewer.answer == f"{done} of 2 steps carried out correctly"


def test_teach_with_a_viewer_that_cannot_start_goes_on_headless_with_one_warning(tmp_path, capsys, monkeypatch):
    def broken(*_args, **_kwargs):
        raise ViewerError("the meshcat server exited while starting: address in use")

    monkeypatch.setattr(viewer_thread, "LocalServer", broken)
    common = ["teach", "--teacher", "scripted", "--seed", "4", "--turns", "4", "--budget", "6", "--change-every",
              "2", "--json", "--no-pictures"]
    assert main([*common, "--transcript", str(tmp_path / "plain.jsonl")]) == 0
    plain = capsys.readouterr()
    assert main([*common, "--transcript", str(tmp_path / "headless.jsonl"), "--viewer"]) == 0
    headless = capsys.readouterr()
    warnings = [line for line in headless.err.splitlines() if line.startswith("warning")]
    assert len(warnings) == 1 and "the viewer did not start" in warnings[0] and "address in use" in warnings[0]
    assert "Viewer:" not in headless.err
    assert without_timing(last_json(headless.out), "transcript") == \
        without_timing(last_json(plain.out), "transcript")


def test_teach_with_a_live_viewer_observes_the_session(tmp_path, capsys, served_pages):
    assert main(["teach", "--teacher", "scripted", "--seed", "4", "--turns", "3", "--budget", "6",
                 "--change-every", "2", "--json", "--no-pictures", "--viewer",
                 "--transcript", str(tmp_path / "viewed.jsonl")]) == 0
    out = capsys.readouterr()
    ((url, status, viewer),) = served_pages
    assert status == 200 and f"Viewer: {url}" in out.err
    assert viewer.question.startswith("Robot:") or viewer.question == "Robot stays quiet."
    assert last_json(out.out)["completed"] == 3


def test_recipe_with_a_viewer_that_cannot_start_goes_on_headless(capsys, monkeypatch):
    def broken(*_args, **_kwargs):
        raise ViewerError("no free port")

    monkeypatch.setattr(viewer_thread, "LocalServer", broken)
    assert main(["recipe", "--recipe", "serve-salad", "--demos", "1", "--viewer", "--json"]) == 0
    out = capsys.readouterr()
    err = [line for line in out.err.splitlines() if line.startswith(("warning", "Viewer"))]
    assert len(err) == 1 and err[0].startswith("warning: the viewer did not start") and "no free port" in err[0]
    assert last_json(out.out)["moved_object_found"] == "2/2"


def test_placed_objects_carry_their_texture_file_and_the_viewer_draws_it_with_the_tint():
    import numpy as np
    import pybullet as p

    from bullet_world import World
    from bullet_world.viewer.scene import WorldReader

    world = World(seed=1)
    try:
        world.new_scene(np.random.default_rng(1))
        frame = WorldReader(world).frame()
        looks = {node: looks for node, (looks, _) in frame.items() if node.startswith("objects/")}
        assert len(looks) == len(world.objects) > 3
        for placed in world.objects:
            assert placed.texture.endswith(".png") and Path(placed.texture).stat().st_size > 100
        drawn = {look.texture for node_looks in looks.values() for look in node_looks}
        assert drawn == {placed.texture for placed in world.objects}
        tint = p.getVisualShapeData(world.objects[0].body, physicsClientId=world.client)[0][7]
        first = next(look for node_looks in looks.values() for look in node_looks
                     if look.texture == world.objects[0].texture)
        assert first.rgba == pytest.approx(tint, abs=1e-4)  # texture x tint, as the TinyRenderer draws it
    finally:
        world.close()
