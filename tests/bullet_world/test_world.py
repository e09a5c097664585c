"""The simulated kitchen: reproducible scenes, perception against the simulator's truth, kitchens."""

import numpy as np
import pytest

from bullet_world import World
from bullet_world.catalogue import DataFileError, load_kitchen, load_task
from bullet_world.check import scene_errors
from bullet_world.kitchen import INTEREST_POINTS

KITCHENS = ("kitchen-1", "kitchen-2", "kitchen-3")


def test_same_seed_same_scene():
    with World(seed=5) as first, World(seed=5) as second:
        a = first.new_scene(np.random.default_rng(11))
        b = second.new_scene(np.random.default_rng(11))
    assert a.feature_names == b.feature_names
    assert np.array_equal(a.X, b.X)
    assert a.truth.kinds == b.truth.kinds and np.array_equal(a.truth.positions, b.truth.positions)


def test_different_seeds_differ():
    with World(seed=5) as world:
        a = world.new_scene(np.random.default_rng(1))
        b = world.new_scene(np.random.default_rng(2))
    assert not np.allclose(a.X, b.X)


def test_sensor_noise_is_seeded_and_can_be_switched_off():
    with World(seed=1) as noisy, World(seed=1, sensor_noise=False) as clean:
        rng_a, rng_b = np.random.default_rng(3), np.random.default_rng(3)
        noisy.new_scene(rng_a)
        clean.new_scene(rng_b)
        first, second = noisy.observe(), noisy.observe()
        assert not np.array_equal(first.X, second.X)  # a new look, new sensor noise
        assert np.array_equal(clean.observe().X, clean.observe().X)


def test_perception_matches_the_simulator(kitchen):
    scene = kitchen.next_scene(np.random.default_rng(7))
    truth = scene.truth
    assert scene.n_objects == kitchen.world.task.objects_per_scene
    assert set(truth.concepts) == set(kitchen.concepts)  # stratified: every concept present
    size_error, location_error = scene_errors(scene)
    assert np.median(size_error) < 0.005 and np.median(location_error) < 0.005
    assert location_error.max() < 0.02


@pytest.mark.parametrize("name", KITCHENS)
def test_every_kitchen_holds_a_scene_and_sees_every_object(name):
    with World(kitchen=name, seed=2, objects_per_scene=20) as world:
        scene = world.new_scene(np.random.default_rng(4))
        kitchen = world.kitchen
        assert scene.n_objects == 20
        assert np.all(kitchen.in_object_region(scene.truth.positions[:, :2]))
        size_error, location_error = scene_errors(scene)
        assert np.median(size_error) < 0.005 and np.median(location_error) < 0.005


def test_kitchens_differ_in_layout_and_objects():
    kitchens = [load_kitchen(name) for name in KITCHENS]
    layouts = {tuple(np.round(k.locations["stove"].centre, 2)) for k in kitchens}
    bases = {(k.robot_base, round(k.robot_yaw, 2)) for k in kitchens}
    assert len(layouts) == 3 and len(bases) == 3
    task = load_task("pack-lunchbox")
    object_sets = {tuple(k.name for k in task.kinds_in(name)) for name in KITCHENS}
    assert len(object_sets) == 3


@pytest.mark.parametrize("name", KITCHENS)
def test_kitchen_locations_are_regions_within_reach(name):
    kitchen = load_kitchen(name)
    assert set(INTEREST_POINTS) <= set(kitchen.locations)
    base = np.asarray(kitchen.robot_base[:2])
    for location in kitchen.locations.values():
        centre, half = np.asarray(location.centre[:2]), np.asarray(location.half_size)
        assert location.contains(centre) and not location.contains(centre + half + 0.01)
        corners = centre + half * np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]])
        distances = np.linalg.norm(corners - base, axis=1)
        assert np.all(distances < 0.8) and np.all(distances >= kitchen.min_reach)


def test_unknown_names_list_what_exists():
    with pytest.raises(DataFileError, match="available: .*pack-lunchbox"):
        load_task("no-such-task")
    with pytest.raises(DataFileError, match="available: .*kitchen-1.*kitchen-3"):
        load_kitchen("kitchen-99")


def test_object_count_outside_the_task_range_is_refused():
    with pytest.raises(ValueError, match="objects_per_scene must be between 4 and 55"):
        World(objects_per_scene=80)


def test_objects_can_be_added_and_removed_by_hand():
    with World(seed=2) as world:
        kind = next(k for k in world.task.kinds if k.name == "apple")
        body = world.add_object(kind, (0.1, 0.0), 0.0, rng=np.random.default_rng(0))
        scene = world.observe()
        assert scene.truth.kinds == ("apple",) and world.object_bodies == (body,)
        assert np.allclose(scene.positions[0, :2], (0.1, 0.0), atol=0.005)
        world.remove_object(body)
        assert world.object_bodies == () and world.observe().X.shape == (0, len(world.feature_names))


def test_a_draw_without_a_colour_index_still_builds():
    with World(seed=2, sensor_noise=False) as world:
        kind = next(k for k in world.task.kinds if k.name == "soda-can")
        draw = {"dimensions": {"radius": 0.032, "height": 0.12}, "colour": [0.8, 0.05, 0.1], "mass": 0.38}
        world.add_object(kind, (0.0, 0.1), 0.3, draw=draw)
        scene = world.observe()
        assert scene.feature("colour.red")[0] > 2 * scene.feature("colour.green")[0]
        assert scene.feature("size.height")[0] == pytest.approx(0.12, abs=0.004)


def test_lighting_changes_measured_colour_but_not_size():
    with World(seed=3, sensor_noise=False) as world:
        before = world.new_scene(np.random.default_rng(5))
        after = world.change_lighting(np.random.default_rng(6))
    brightness = before.feature("colour.value") - after.feature("colour.value")
    assert np.abs(brightness).mean() > 0.02
    assert np.array_equal(before.feature("size.length"), after.feature("size.length"))
    assert before.feature("light.level")[0] != after.feature("light.level")[0]
