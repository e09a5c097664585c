"""The embodied suite's scene size as the docs and the suite file state it is what runs (issue 42, case 6)."""

from pathlib import Path

from bullet_world.catalogue import load_task
from dialog.experiments.suite import load_suite
from learning.strategies import STRATEGY_NAMES

ROOT = Path(__file__).resolve().parents[2]


def test_the_embodied_suite_runs_twelve_objects_a_scene_and_says_so():
    suite = load_suite("embodied", STRATEGY_NAMES)
    sizes = {condition.scene_size(load_task(suite.task).objects_per_scene) for condition in suite.conditions}
    assert sizes == {12}
    docs = " ".join((ROOT / "docs" / "experiments.md").read_text().split())
    assert "`embodied` set `objects_per_scene = 55`" not in docs
    assert "`dialog/suites/embodied.toml`: pack-lunchbox (12 objects a scene" in docs
    comment = " ".join((ROOT / "dialog" / "suites" / "embodied.toml").read_text().split())
    assert "55 objects a scene in the data sets" not in comment and "12 objects a scene" in comment
