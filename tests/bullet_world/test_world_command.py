"""``teachbot world show`` and ``teachbot world check`` through the command line."""

import json

import cv2

from dialog.cli import main


def test_world_show_writes_an_annotated_picture(tmp_path, capsys):
    out = tmp_path / "scene.png"
    assert main(["world", "show", "--kitchen", "kitchen-2", "--seed", "3", "--objects", "8", "--png", str(out)]) == 0
    picture = cv2.imread(str(out))
    assert picture is not None and picture.shape[0] > 300
    printed = capsys.readouterr().out
    assert "in kitchen-2 (seed 3): 8 objects" in printed and "\n    8  " in printed and f"Picture: {out}" in printed


def test_world_show_refuses_a_bad_file_name(tmp_path, capsys):
    assert main(["world", "show", "--png", str(tmp_path / "scene.jpg")]) == 2
    assert "--png must name a .png file" in capsys.readouterr().err


def test_world_check_ends_with_one_json_line(capsys):
    assert main(["world", "check", "--objects", "12", "--per-scene", "6", "--kitchen", "kitchen-1",
                 "--json"]) == 0
    captured = capsys.readouterr()
    assert "scene 2: 6 objects in this scene, 12 in total so far (of at least 12)" in captured.err  # totals say so
    assert captured.out.startswith("12 objects in 2 scenes (kitchen-1): ")
    result = json.loads(captured.out.strip().splitlines()[-1])
    assert set(result) >= {"objects", "size_err_mm", "loc_err_mm", "features", "ms_per_scene"}
    assert result["objects"] >= 12 and set(result["size_err_mm"]) == {"median", "p95"}
    assert result["size_err_mm"]["median"] < 5 and result["loc_err_mm"]["median"] < 5


def test_world_data_builds_then_reuses_the_cache(tmp_path, capsys):
    arguments = ["world", "data", "--task", "prepare-lunch", "--no-robot", "--cache", str(tmp_path), "--json",
                 "--pool-size", "80", "--test-size", "40"]
    assert main(arguments) == 0
    first_lines = capsys.readouterr().out.strip().splitlines()
    first = json.loads(first_lines[-1])
    assert first["train"] == [80] * 5 and first["test"] == 40 and first["features"] == 56
    assert main(arguments) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out.strip().splitlines()[-1])["file"] == first["file"]
    assert "pool" not in captured.err  # nothing rendered the second time
    assert "built in" in first_lines[0] and "cache" not in first_lines[0]
    assert ": 5 training pools of 80" in captured.out and "; loaded from the cache in " in captured.out
