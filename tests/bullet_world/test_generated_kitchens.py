"""Kitchens generated from a seed (issue 52): reproducible to the byte, valid and within reach, checked small like
the shipped three (perception bands, pointing with no room contact, one pick-and-place), accepted by path, and
every bad generator data file or generated kitchen refused in one line naming the field."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bullet_world.check import scene_errors, timed_scene
from bullet_world.generation import DEFAULT_DISTRIBUTIONS, generate_kitchens, load_distributions
from bullet_world.generation.writer import generate_kitchen
from bullet_world.kitchen import ARM_REACH_M, INTEREST_POINTS, load_kitchen
from bullet_world.recipes.setup import load_recipe_setup
from bullet_world.world import World
from tests.datafile_edits import changed, refused
from tests.scripts import load_script

SEEDS = (9001, 9002, 9003)   # seeds no doc uses
DATA = DEFAULT_DISTRIBUTIONS.read_text()


@pytest.fixture(scope="module")
def kitchens(tmp_path_factory):
    return generate_kitchens(SEEDS[0], len(SEEDS), tmp_path_factory.mktemp("kitchens"))


def test_the_same_seed_gives_the_same_bytes_whatever_the_count(kitchens, tmp_path):
    alone = generate_kitchens(SEEDS[1], 1, tmp_path)[0]
    assert alone.read_bytes() == kitchens[1].read_bytes()
    assert len({path.read_bytes() for path in kitchens}) == len(kitchens)
    assert [path.name for path in kitchens] == [f"generated-{seed}.toml" for seed in SEEDS]


def test_forty_seeds_draw_every_family():
    distributions = load_distributions()
    families = set()
    for seed in range(5000, 5040):
        _, text = generate_kitchen(seed, distributions)
        families.add(text.split('family = "')[1].split('"')[0])
    assert families == {family.name for family in distributions.families}


def test_generated_kitchens_load_with_their_households_and_every_location_in_reach(kitchens):
    for path in kitchens:
        kitchen = load_kitchen(path)
        assert kitchen.generated["seed"] in SEEDS and kitchen.room is not None
        assert set(kitchen.locations) == set(INTEREST_POINTS)
        base = np.asarray(kitchen.robot_base[:2])
        for location in kitchen.locations.values():
            (cx, cy, _), (hx, hy) = location.centre, location.half_size
            for corner in ((cx - hx, cy - hy), (cx + hx, cy - hy), (cx + hx, cy + hy), (cx - hx, cy + hy)):
                distance = float(np.hypot(*(np.asarray(corner) - base)))
                assert kitchen.min_reach <= distance <= min(kitchen.max_reach, ARM_REACH_M)
            assert kitchen.in_object_region(np.asarray(location.centre[:2]))[0]
        for task in ("serve-pasta", "serve-salad"):
            household = load_recipe_setup(task).household_for(kitchen)
            assert household.name == kitchen.name and household.roles()


@pytest.mark.parametrize("index", range(len(SEEDS)))
def test_world_check_stays_within_the_shipped_bands(kitchens, index):
    """Two scenes of 55 objects with the arm: size and location error medians within 5 mm."""
    from robot import Arm

    sizes, locations = [], []
    with World(kitchen=str(kitchens[index]), seed=index, objects_per_scene=55) as world:
        Arm(world)
        for scene_index in range(2):
            scene, _, _ = timed_scene(world, np.random.default_rng([index, scene_index]))
            size, location = scene_errors(scene)
            sizes.append(size)
            locations.append(location)
    assert np.median(np.concatenate(sizes)) <= 0.005
    assert np.median(np.concatenate(locations)) <= 0.005


@pytest.mark.parametrize("index", range(len(SEEDS)))
def test_the_arm_points_at_every_object_without_touching_the_room(kitchens, index):
    check = load_script("check_generated_kitchens")
    result = check.pointing(str(kitchens[index]), SEEDS[index])
    assert result["missed"] == 0 and result["touched"] == [] and result["objects"] > 0


def test_pick_and_place_moves_one_object(kitchens):
    check = load_script("check_generated_kitchens")
    result = check.pick_place(str(kitchens[0]), 1, SEEDS[0])
    assert result["successes"] == 1, result


@pytest.mark.parametrize("old, new, fragments", [
    ('weight = 1.0\ndescription = "Galley', 'weight = -1.0\ndescription = "Galley', ("[families.galley]", "'weight'")),
    ("back_run = true\nback_gap = [0.90", "back_run = 1\nback_gap = [0.90", ("[families.galley]", "'back_run'")),
    ('floor = ["terracotta"', 'floor = ["carpet"', ("[palette]", "unknown material 'carpet'")),
    ('fixture = "cooktop"', 'fixture = "oven"', ("[locations.stove]", "fixture 'oven' is not one of")),
    ('"steel-pot", "red-enamel-pot"', '"steel-pot", "teapot"', ("[households.serve-pasta] roles 1", "'teapot'")),
    ("location_reach = [0.37, 0.72]", "location_reach = [0.30, 0.72]", ("[reach]", "'location_reach'")),
    ("tries = 400", "tires = 400", ("[reach]", "did you mean 'tries'")),
    ('colours = ["warm-white"', 'colours = ["disco"', ("[lighting]", "'disco'")),
    ("[households.serve-salad]", "[households.bake-bread]", ("[households.bake-bread]", "no task 'bake-bread'")),
])
def test_a_bad_generator_file_names_the_file_and_field(tmp_path, old, new, fragments):
    path = tmp_path / "kitchens.toml"
    path.write_text(changed(DATA, old, new))
    refused(load_distributions, path, *fragments)


def test_arrangements_that_cannot_fit_are_one_line(tmp_path):
    path = tmp_path / "kitchens.toml"
    path.write_text(changed(changed(DATA, "location_reach = [0.37, 0.72]", "location_reach = [0.37, 0.40]"),
                            "tries = 400", "tries = 3"))
    with pytest.raises(ValueError) as caught:
        generate_kitchens(1, 1, tmp_path / "out", path)
    assert "\n" not in str(caught.value) and "no arrangement of the five locations" in str(caught.value)


@pytest.mark.parametrize("old, new, fragments", [
    ('at = "stove" }', 'at = "garage" }', ("[households.serve-pasta] object 1", "at 'garage' is not one of")),
    ("seed = 9001", "seed = -4", ("[generated]", "'seed'")),
    ('{ kind = "', '{ knd = "', ("[households.serve-pasta] object 1", "did you mean 'kind'")),
])
def test_a_bad_generated_kitchen_names_the_file_and_field(kitchens, tmp_path, old, new, fragments):
    text = kitchens[0].read_text()
    first = text.index(old)
    path = tmp_path / "kitchen.toml"
    path.write_text(text[:first] + new + text[first + len(old):])
    refused(load_kitchen, path, *fragments)


def test_a_household_kind_the_task_lacks_is_refused_when_the_recipe_uses_it(kitchens, tmp_path):
    text = kitchens[0].read_text()
    path = tmp_path / "kitchen.toml"
    kind = text.split("[households.serve-pasta]")[1].split('kind = "')[1].split('"')[0]
    path.write_text(text.replace(f'{{ kind = "{kind}", role = "pasta-pot"', '{ kind = "teapot", role = "pasta-pot"'))
    refused(lambda p: load_recipe_setup("serve-pasta").household_for(load_kitchen(p)), path,
            "[households.serve-pasta]", "unknown kind 'teapot'")


def test_the_camera_sees_the_whole_reachable_region(kitchens):
    for path in kitchens:
        kitchen = load_kitchen(path)
        camera = kitchen.camera
        half_height = math.tan(math.radians(camera["fov_degrees"]) / 2) * camera["eye"][2]
        half_width = half_height * camera["width"] / camera["height"]
        xs, ys = np.meshgrid(np.linspace(*kitchen.region_x, 60), np.linspace(*kitchen.region_y, 60))
        grid = np.column_stack([xs.ravel(), ys.ravel()])
        reachable = grid[kitchen.in_object_region(grid)]
        assert np.all(np.abs(reachable[:, 0] - camera["target"][0]) <= half_width - 0.1)
        assert np.all(np.abs(reachable[:, 1] - camera["target"][1]) <= half_height - 0.1)
