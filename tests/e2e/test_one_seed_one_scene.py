"""One seed, one scene: ``world show``, ``view`` and ``demo`` with the same seed show the same first scene."""

from contextlib import contextmanager

import numpy as np
import pytest

import dialog.commands.demo as demo_command
import dialog.commands.world as world_command
from dialog.cli import main

pytestmark = pytest.mark.e2e


def _table(printed: str) -> list[str]:
    """The scene table's lines (header and one line per object) from a command's output."""
    lines = printed.splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip().startswith("no.  object"))
    table = [lines[start]]
    for line in lines[start + 1:]:
        if not line.startswith("  ") or not line.strip()[:1].isdigit():
            break
        table.append(line)
    return table


@pytest.mark.parametrize("seed, kitchen", [(0, "kitchen-1"), (4, "2")])
def test_world_show_view_and_demo_show_the_same_first_scene(seed, kitchen, tmp_path, capsys, monkeypatch):
    shown = []
    table = world_command.scene_table
    monkeypatch.setattr(world_command, "scene_table", lambda scene, env: shown.append(scene) or table(scene, env))
    assert main(["world", "show", "--seed", str(seed), "--kitchen", kitchen]) == 0
    show_table = _table(capsys.readouterr().out)
    assert len(show_table) == shown[0].n_objects + 1

    assert main(["view", "--seed", str(seed), "--kitchen", kitchen, "--seconds", "0"]) == 0
    assert _table(capsys.readouterr().out) == show_table  # same objects, numbers, colours, sizes and places

    seen = []

    class FirstScene:  # an observer of the demo's episode
        def on_scene(self, scene):
            seen.append(scene)

    @contextmanager
    def observers(args, world):
        yield (FirstScene(),)

    monkeypatch.setattr(demo_command, "viewer_observers", observers)
    assert main(["demo", "--seed", str(seed), "--kitchen", kitchen, "--turns", "1", "--transcript",
                 str(tmp_path / "demo.jsonl")]) == 0
    listed, demo = shown[0].truth, seen[0].truth  # the perceived features differ by sensor noise only
    assert demo.kinds == listed.kinds and demo.concepts == listed.concepts and demo.states == listed.states
    np.testing.assert_allclose(demo.positions, listed.positions, atol=1e-6)


def test_world_show_prints_a_table_without_a_picture(capsys, tmp_path):
    assert main(["world", "show", "--seed", "3", "--kitchen", "kitchen-2", "--objects", "8"]) == 0
    printed = capsys.readouterr().out
    table = _table(printed)
    assert table[0].split()[:5] == ["no.", "object", "concept", "colour", "size"]
    assert len(table) == 9 and table[-1].split()[0] == "8"
    assert "8 objects" in printed and not list(tmp_path.iterdir())
