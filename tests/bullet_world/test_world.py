"""The simulated kitchen: reproducible scenes, perception against the simulator's truth."""

import numpy as np
import pytest

from bullet_world import World
from bullet_world.catalogue import DataFileError, load_kitchen, load_object_kinds, load_task


def test_same_seed_same_scene():
    with World(seed=5) as first, World(seed=5) as second:
        a = first.new_scene(np.random.default_rng(11))
        b = second.new_scene(np.random.default_rng(11))
    assert a.feature_names == b.feature_names
    assert np.array_equal(a.X, b.X)
    assert a.truth.kinds == b.truth.kinds


def test_different_seeds_differ():
    with World(seed=5) as world:
        a = world.new_scene(np.random.default_rng(1))
        b = world.new_scene(np.random.default_rng(2))
    assert not np.allclose(a.X, b.X)


def test_perception_matches_the_simulator(kitchen):
    scene = kitchen.next_scene(np.random.default_rng(7))
    truth = scene.truth
    assert scene.n_objects == kitchen.world.task.objects_per_scene
    assert set(truth.concepts) == set(kitchen.concepts)  # stratified: every concept present
    size_error = np.abs(np.column_stack([scene.feature("size.length"), scene.feature("size.width"),
                                         scene.feature("size.height")]) - truth.sizes)
    location_error = np.linalg.norm(scene.positions[:, :2] - truth.positions[:, :2], axis=1)
    assert np.median(size_error) < 0.005 and size_error.max() < 0.02
    assert np.median(location_error) < 0.005 and location_error.max() < 0.015


def test_robot_features_join_the_feature_vector(kitchen):
    names = kitchen.feature_names
    assert "arm.joint1" in names and "hand.z" in names and names[0] == "colour.red"
    scene = kitchen.next_scene(np.random.default_rng(8))
    assert scene.X.shape == (scene.n_objects, len(names))
    joint = scene.feature("arm.joint4")
    assert np.all(joint == joint[0])  # one arm state per observation


def test_unknown_names_list_what_exists():
    with pytest.raises(DataFileError, match="available: .*pack-lunchbox"):
        load_task("no-such-task")
    with pytest.raises(DataFileError, match="available: .*kitchen-1"):
        load_kitchen("kitchen-99")


def test_broken_object_file_names_the_field(tmp_path):
    path = tmp_path / "objects.toml"
    path.write_text('[[kind]]\nname = "x"\nconcept = "fruit"\nshape = "cube"\n')
    with pytest.raises(DataFileError, match="shape 'cube' is not one of box, cylinder, sphere"):
        load_object_kinds(path)
    path.write_text('[[kind]]\nname = "x"\nconcept = "fruit"\nshape = "sphere"\nradius = [0.05]\n'
                    'colours = [[1, 0, 0]]\ncolour_jitter = 0.0\nmass = [0.1, 0.2]\n')
    with pytest.raises(DataFileError, match="'radius' must be a list of 2 numbers"):
        load_object_kinds(path)
    path.write_text("this is = = not toml")
    with pytest.raises(DataFileError, match="not valid TOML"):
        load_object_kinds(path)


def test_kitchen_locations_are_regions_within_reach():
    kitchen = load_kitchen("kitchen-1")
    assert {"stove", "fridge", "cupboard", "pantry", "counter"} <= set(kitchen.locations)
    base = np.asarray(kitchen.robot_base[:2])
    for location in kitchen.locations.values():
        assert location.contains(location.centre[:2])
        corner = np.asarray(location.centre[:2]) + np.asarray(location.half_size)
        assert not location.contains(corner + 0.01)
        assert np.linalg.norm(np.asarray(location.centre[:2]) - base) < 0.8


def test_every_feature_has_a_name_group_and_description(kitchen):
    from bullet_world.features import feature_info

    infos = feature_info(kitchen.feature_names)
    assert [info.name for info in infos] == list(kitchen.feature_names)
    for info in infos:
        assert info.group.count("/") >= 1 and len(info.description) > 15


def test_objects_can_be_added_and_removed_by_hand():
    with World(seed=2) as world:
        kind = next(k for k in world.task.kinds if k.name == "apple")
        body = world.add_object(kind, (0.1, 0.0), 0.0, rng=np.random.default_rng(0))
        scene = world.observe()
        assert scene.truth.kinds == ("apple",) and world.object_bodies == (body,)
        assert np.allclose(scene.positions[0, :2], (0.1, 0.0), atol=0.005)
        world.remove_object(body)
        assert world.object_bodies == () and world.observe().X.shape == (0, len(world.feature_names))
