"""``teachbot teach`` with scripted and replay teachers in the real kitchen; pictures and the pantry."""

import json

import cv2
import numpy as np
import pytest

from dialog.cli import main
from dialog.transcripts.jsonl import read_session

pytestmark = pytest.mark.e2e


def teach(capsys, *args):
    assert main(["teach", "--turns", "10", "--budget", "20", "--change-every", "5", "--strategy", "all-cd",
                 "--json", *map(str, args)]) == 0
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def test_scripted_then_replayed_sessions(tmp_path, capsys):
    first = tmp_path / "scripted.jsonl"
    summary = teach(capsys, "--teacher", "scripted", "--mislabel-rate", "0.2", "--seed", "3", "--transcript", first,
                    "--pictures", tmp_path / "pictures")
    assert summary["completed"] == 10 and summary["budget_spent"] <= 20 and not summary["quit"]
    header, records = read_session(first)
    assert header["teacher"]["kind"] == "scripted" and header["teacher"]["mislabel_rate"] == 0.2
    assert records[0]["action"] == {"kind": "feature"}
    assert records[0]["answer"]["parsed"] and records[0]["model"]["features_in_use"] < header["features"]
    pictures = [r["picture"] for r in records if "picture" in r]
    assert pictures and all(cv2.imread(p) is not None for p in pictures)

    again = tmp_path / "again.jsonl"
    teach(capsys, "--teacher", "scripted", "--mislabel-rate", "0.2", "--seed", "3", "--transcript", again,
          "--pictures", tmp_path / "pictures")
    assert again.read_bytes() == first.read_bytes()

    replayed = tmp_path / "replayed.jsonl"
    teach(capsys, "--teacher", "replay", "--replay", first, "--seed", "3", "--transcript", replayed, "--no-pictures")
    strip = ("picture",)
    original = [{k: v for k, v in r.items() if k not in strip} for r in records]
    assert [{k: v for k, v in r.items() if k not in strip} for r in read_session(replayed)[1]] == original


def test_an_existing_transcript_is_not_overwritten(tmp_path, capsys):
    path = tmp_path / "taken.jsonl"
    path.write_text('{"turn": 1}\n')
    assert main(["teach", "--teacher", "scripted", "--transcript", str(path)]) == 2
    assert "--resume" in capsys.readouterr().err


def test_fetching_from_the_pantry_observes_a_new_object_and_puts_it_back(kitchen):
    rng = np.random.default_rng(5)
    scene = kitchen.next_scene(rng)
    bodies = kitchen.world.object_bodies
    assert kitchen.can_fetch("fruit")
    fetched = kitchen.fetch(scene, "fruit", rng)
    assert fetched is not None and fetched["x"].shape == (len(kitchen.feature_names),)
    assert kitchen.world.object_bodies == bodies
    pantry = kitchen.world.kitchen.locations["pantry"]
    assert pantry.contains(fetched["position"])
    assert fetched["kind"] in {k.name for k in getattr(kitchen.world, "kinds", kitchen.world.task.kinds)
                               if k.concept == "fruit"}
    size = fetched["x"][list(kitchen.feature_names).index("size.height")]
    assert 0.02 < size < 0.3


def test_the_numbered_picture_rings_the_object_asked_about(kitchen, tmp_path):
    scene = kitchen.next_scene(np.random.default_rng(8))
    path = kitchen.scene_picture(scene, tmp_path / "p.png", highlight=2)
    image = cv2.imread(str(path))
    assert image.shape[:2] == (kitchen.world.camera.height, kitchen.world.camera.width)
    _, _, pixels, _ = kitchen._scene_image
    column, row = (int(round(v)) for v in pixels[2])
    window = image[max(row - 40, 0):row + 40, max(column - 40, 0):column + 40]
    ring = np.all(np.abs(window.astype(int) - (0, 215, 255)) < 40, axis=2)
    assert ring.sum() > 50


def test_the_arm_points_above_every_object_even_at_the_edge_of_reach(kitchen):
    rng = np.random.default_rng(11)
    reports = []
    for _ in range(2):
        scene = kitchen.next_scene(rng)
        reports += [kitchen.point_at(scene, index) for index in range(scene.n_objects)]
    assert all(r["reached"] and r["horizontal_error_m"] < 0.02 for r in reports), reports
    assert all(0.0 < r["height_above_top_m"] <= 0.3 for r in reports)
    assert np.median([r["height_above_top_m"] for r in reports]) < 0.1  # most from the usual 8 cm
