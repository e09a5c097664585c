"""Fetching from the pantry never ends a session (issue 13, case 1), in the real PyBullet kitchen."""

import io

import numpy as np
import pybullet as p
import pytest

import dialog.environment as environment
from bullet_world.world import HiddenObjectError
from dialog.cli import main
from dialog.environment import SimulatedKitchen
from dialog.transcripts.jsonl import read_session

pytestmark = pytest.mark.e2e

ANSWERS = ["fruit", "main dish", "none", "1.1, 1.2", "none", "none"]


def _teach(monkeypatch, capsys, lines, *args) -> tuple[int, str]:
    monkeypatch.setattr("sys.stdin", io.StringIO("".join(f"{line}\n" for line in lines)))
    code = main(["teach", "--no-pictures", *map(str, args)])
    captured = capsys.readouterr()
    return code, captured.out + captured.err


@pytest.mark.parametrize("seed", [11, 12])
def test_saying_none_to_show_me_questions_keeps_the_session_going_and_resumable(seed, tmp_path, monkeypatch, capsys):
    path = tmp_path / "session.jsonl"
    code, out = _teach(monkeypatch, capsys, ANSWERS, "--seed", seed, "--turns", 20, "--budget", 30,
                       "--transcript", path)
    assert code == 0, out
    assert "not visible" not in out and "Session saved after" in out
    _, records = read_session(path)
    absent = [r for r in records if r["action"]["kind"] == "demo" and "fetched" in r]
    assert len(absent) >= 2  # every "none" to a "show me" question brought an example from the pantry
    # told in words, as the robot describes any object, never by the catalogue's kind name (issue 50)
    told = [line for line in out.splitlines() if "so I fetched one from the pantry" in line]
    assert len(told) == len(absent) and all(": the " in line for line in told), told
    assert not any(record["fetched"]["kind"] in line for record in absent for line in told), told

    # "none" answers a show-me question, "fruit" a label question (re-asked after the "none"): the resumed
    # session goes on whichever it asks (which one can turn on a tie between two equally good demos)
    code, out = _teach(monkeypatch, capsys, ["none", "fruit"] * 3, "--resume", path)
    assert code == 0, out
    assert "not visible" not in out and "did not repeat" not in out
    _, resumed = read_session(path)
    assert resumed[:len(records)] == records and len(resumed) > len(records)


def _poses(kitchen):
    return np.array([p.getBasePositionAndOrientation(obj.body, physicsClientId=kitchen.world.client)[0]
                     for obj in kitchen.world.objects])


@pytest.mark.parametrize("task, kitchen_name", [("pack-lunchbox", "kitchen-1"), ("prepare-lunch", "kitchen-2"),
                                                ("sort-groceries", "kitchen-3")])
def test_many_fetches_never_raise_and_leave_the_scene_as_it_was(task, kitchen_name):
    kitchen = SimulatedKitchen(task=task, kitchen=kitchen_name, seed=5)
    rng = np.random.default_rng(9)
    try:
        fetched = 0
        for _ in range(4):
            scene = kitchen.next_scene(rng)
            before = _poses(kitchen)
            for concept in kitchen.concepts:
                result = kitchen.fetch(scene, concept, rng)
                assert result is not None and result["x"] is not None, result
                assert result["x"].shape == (len(kitchen.feature_names),) and np.all(np.isfinite(result["x"]))
                fetched += 1
            assert np.allclose(_poses(kitchen), before, atol=1e-6)  # the reach knocked nothing over
            assert kitchen.world.scene is scene and len(kitchen.world.objects) == scene.n_objects
        assert fetched >= 12
    finally:
        kitchen.close()


def test_the_same_pantry_stream_fetches_the_same_object_at_the_same_spot():
    results = []
    for _ in range(2):
        kitchen = SimulatedKitchen(seed=4)
        try:
            scene = kitchen.next_scene(np.random.default_rng(1))
            rng = np.random.default_rng(2)
            results.append([kitchen.fetch(scene, concept, rng) for concept in kitchen.concepts])
        finally:
            kitchen.close()
    for first, second in zip(*results):
        assert first["kind"] == second["kind"] and first["position"] == second["position"]


def test_a_full_pantry_lends_the_place_of_an_object_of_another_concept(monkeypatch):
    kitchen = SimulatedKitchen(seed=6)
    try:
        scene = kitchen.next_scene(np.random.default_rng(3))
        monkeypatch.setattr(environment, "free_spots", lambda *args, **kwargs: [])
        before = _poses(kitchen)
        result = kitchen.fetch(scene, "fruit", np.random.default_rng(4))
        assert result["x"] is not None and result["replaced"]
        replaced = next(obj for obj in kitchen.world.objects if obj.kind.name == result["replaced"])
        assert replaced.kind.concept != "fruit"
        assert np.allclose(_poses(kitchen), before, atol=1e-6)  # the object set aside is back where it stood
        assert len(kitchen.world.objects) == scene.n_objects
    finally:
        kitchen.close()


def test_a_fetch_the_camera_cannot_see_is_told_in_the_dialog_and_recorded_as_absent(tmp_path, monkeypatch, capsys):
    def hidden(*args):
        raise HiddenObjectError("objects not visible to the camera: test")

    monkeypatch.setattr(environment, "glimpse", hidden)
    path = tmp_path / "session.jsonl"
    code, out = _teach(monkeypatch, capsys, ANSWERS, "--seed", 11, "--turns", 20, "--budget", 30,
                       "--transcript", path)
    assert code == 0, out
    assert "I couldn't fetch one from the pantry" in out
    _, records = read_session(path)
    failed = [r for r in records if "fetch_failed" in r]
    assert failed and all(r["answer"]["kind"] == "absent" and "fetched" not in r for r in failed)
    assert len(records) > records.index(failed[0]) + 1  # the session went on after the failed fetch
