"""The distance between two kitchens for a recipe (bullet_world/recipes/distance.py, the transfer plan's d)."""

import numpy as np
import pytest

from bullet_world.generation import cached_kitchens
from bullet_world.kitchen import load_kitchen
from bullet_world.recipes.distance import kitchen_distance, location_centres

SALAD = [("bowl", "cupboard", "counter"), ("salad-dressing", "fridge", "counter")]


def test_a_kitchen_is_at_distance_zero_from_itself_and_the_distance_is_symmetric():
    assert kitchen_distance(SALAD, "serve-salad", "kitchen-2", "kitchen-2").total == 0.0
    ab = kitchen_distance(SALAD, "serve-salad", "kitchen-1", "kitchen-3")
    ba = kitchen_distance(SALAD, "serve-salad", "kitchen-3", "kitchen-1")
    assert ab == ba and ab.total > 0


def test_the_distance_sums_the_moves_in_tenths_of_a_metre_and_the_dishes_that_differ():
    a, b = load_kitchen("kitchen-1"), load_kitchen("kitchen-2")
    names = ["cupboard", "counter", "fridge"]
    moved = np.linalg.norm(location_centres(a, names) - location_centres(b, names), axis=1).sum() / 0.10
    distance = kitchen_distance(SALAD, "serve-salad", a, b)
    # home-1 and home-2 keep another bowl and another dressing (bullet_world/data/tasks/serve-salad.toml)
    assert distance.displacement == pytest.approx(moved) and distance.appearance == 2
    assert distance.total == pytest.approx(moved + 2)


def test_locations_are_seen_from_the_robot():
    kitchen = load_kitchen("kitchen-1")
    c, s = np.cos(kitchen.robot_yaw), np.sin(kitchen.robot_yaw)
    centre = np.array(kitchen.locations["fridge"].centre[:2]) - kitchen.robot_base[:2]
    assert location_centres(kitchen, ["fridge"])[0] == pytest.approx([c * centre[0] + s * centre[1],
                                                                      -s * centre[0] + c * centre[1]])


def test_a_recipe_location_the_kitchen_lacks_is_one_clear_error():
    with pytest.raises(ValueError, match="has no location 'cellar' that the recipe uses"):
        kitchen_distance([("bowl", "cellar", "counter")], "serve-salad", "kitchen-1", "kitchen-2")


def test_generated_kitchens_by_seed_range_are_written_once_to_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("TEACHBOT_CACHE", str(tmp_path))
    first = cached_kitchens(9001, 9002)
    assert [p.rsplit("/", 1)[-1] for p in first] == ["generated-9001.toml", "generated-9002.toml"]
    stamps = [tmp_path.joinpath(p).stat().st_mtime_ns for p in first]
    assert cached_kitchens(9001, 9002) == first and [tmp_path.joinpath(p).stat().st_mtime_ns for p in first] == stamps
    assert load_kitchen(first[0]).generated["seed"] == 9001
