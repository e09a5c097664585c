"""The viewer wired into commands: ``--viewer`` options, going headless on failure, an episode's page."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from bullet_world.viewer import thread as viewer_thread
from bullet_world.viewer.server import ViewerError
from dialog.viewer import add_viewer_option, start_viewer, stop_viewer, viewer_observers
from tests.bullet_world.test_viewer import BareWorld


def parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_viewer_option(parser)
    return parser.parse_args(list(argv))


def test_no_option_no_viewer():
    world = BareWorld()
    try:
        assert start_viewer(parse(), world) is None
        with viewer_observers(parse(), world) as observers:
            assert observers == ()
    finally:
        world.close()


def test_a_viewer_that_cannot_start_leaves_one_warning_line_and_the_session_headless(monkeypatch, capsys):
    def broken(*_args, **_kwargs):
        raise ViewerError("the meshcat server exited while starting: address in use")

    monkeypatch.setattr(viewer_thread, "LocalServer", broken)
    world = BareWorld()
    try:
        with viewer_observers(parse("--viewer"), world) as observers:
            assert observers == ()
    finally:
        world.close()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("warning: the viewer did not start") and "address in use" in err[0]


def test_live_viewer_prints_its_loopback_url_and_closes(capsys):
    world = BareWorld()
    world.three_objects()
    try:
        viewer = start_viewer(parse("--viewer"), world)
        assert viewer is not None and viewer.url.startswith("http://127.0.0.1:")
        assert capsys.readouterr().err.strip() == f"Viewer: {viewer.url}"
        assert stop_viewer(viewer) is None and viewer.thread.server is None
    finally:
        world.close()


@pytest.mark.e2e
def test_an_episode_with_viewer_export_writes_its_page(tmp_path, capsys):
    from dialog.environment import SimulatedKitchen
    from dialog.manager import DialogManager, EpisodeConfig, episode_generators
    from dialog.teachers.scripted import OracleTeacher
    from dialog.transcripts.jsonl import TranscriptWriter
    from learning.strategies import make_strategy

    page = tmp_path / "episode.html"
    environment = SimulatedKitchen(seed=4)
    rngs = episode_generators(4)
    try:
        with viewer_observers(parse("--viewer-export", str(page)), environment.world) as observers, \
                TranscriptWriter(tmp_path / "run.jsonl") as transcript:
            (viewer,) = observers
            manager = DialogManager(environment, OracleTeacher(rngs["teacher"]), make_strategy("passive"),
                                    EpisodeConfig(turns=3, budget=10, change_every=2, seed=4), transcript, rngs,
                                    say=lambda *_: None, observers=observers)
            manager.run()
    finally:
        environment.close()
    assert page.is_file() and page.stat().st_size > 500_000
    assert viewer.url is None and viewer.recording.samples > 10
    texts = {look.text for version in viewer.recording.versions for look in version.looks if look.shape == "text"}
    questions = [t for t in texts if t.startswith("Robot:")]
    assert questions and any(t.startswith("Teacher:") and t != "Teacher: …" for t in texts)
    scenes = {v.node for v in viewer.recording.versions if v.node.startswith("objects/")}
    assert len(scenes) >= 2 * environment.world.task.objects_per_scene  # two scenes, each object its own node
    assert "Episode page:" in capsys.readouterr().err
    assert Path(page).read_text(encoding="utf-8").count("fetch(") > 100


def test_view_rejects_an_object_number_outside_the_scene(capsys):
    from dialog.cli import main

    assert main(["view", "--seed", "2", "--point", "40", "--seconds", "0"]) == 2
    assert "--point 40: the scene has objects 1 to" in capsys.readouterr().err


def test_view_export_names_its_page_and_how_to_open_it_and_no_url_of_a_server_that_exits(tmp_path, capsys,
                                                                                          monkeypatch):
    """Issue 51: the command returns once the page is written, so the page is what it points to, not the URL."""
    from dialog.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["view", "--seed", "2", "--export", "scene.html"]) == 0
    out = capsys.readouterr().out
    assert "Viewer:" not in out and "http://" not in out and "Serving" not in out
    (line,) = [line for line in out.splitlines() if line.startswith("Page: ")]
    assert line.startswith("Page: scene.html (") and "one self-contained HTML file that needs no server" in line
    assert line.endswith(f"open it in a web browser: {(tmp_path / 'scene.html').as_uri()}")
    assert (tmp_path / "scene.html").stat().st_size > 10_000
