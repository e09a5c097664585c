"""The feature catalogue: names, hierarchy and descriptions; values that mean what they say."""

import numpy as np
import pytest

from bullet_world import World
from bullet_world.catalogue import DataFileError, load_task
from bullet_world.features import (
    SOURCES,
    environment_feature_catalogue,
    feature_catalogue,
    feature_info,
    object_feature_catalogue,
    resolve_feature_patterns,
    robot_feature_catalogue,
)
from bullet_world.kitchen import INTEREST_POINTS


def test_every_feature_has_a_name_a_group_and_a_description():
    catalogue = feature_catalogue()
    assert 80 <= len(catalogue) <= 100  # "about 90" (thesis: 84 and 90)
    names = [info.name for info in catalogue]
    assert len(set(names)) == len(names)
    for info in catalogue:
        assert info.name and info.source in SOURCES
        assert info.group.split("/")[0] in ("object", "environment", "robot") and info.group.count("/") >= 1
        assert len(info.description) > 20 and info.description[0].isupper()
    assert {"object/appearance/colour", "object/appearance/texture", "object/geometry/shape",
            "object/location/stove", "environment/noise", "robot/hand/counter"} <= {i.group for i in catalogue}


def test_the_world_lists_object_then_room_then_robot_features(kitchen):
    names = kitchen.feature_names
    expected = object_feature_catalogue() + environment_feature_catalogue() + robot_feature_catalogue()
    assert names == tuple(info.name for info in expected)
    assert [info.name for info in feature_info(names)] == list(names)
    with pytest.raises(KeyError, match="no-such-feature"):
        feature_info(["no-such-feature"])


def test_relevant_features_resolve_groups_to_names():
    task = load_task("pack-lunchbox")
    relevant = task.relevant_features
    assert "colour.red" in relevant and "texture.keypoints" in relevant and "weight" in relevant
    assert not any(name.startswith(("location.", "arm.", "hand.", "noise.")) for name in relevant)
    lunch = load_task("prepare-lunch").relevant_features
    assert "location.stove.distance" in lunch and "location.robot.distance" not in lunch
    assert resolve_feature_patterns(["colour"]) == tuple(n for n in relevant if n.startswith("colour."))
    with pytest.raises(DataFileError, match="'object/smell' names no feature"):
        resolve_feature_patterns(["object/smell"], "test")


def test_feature_values_mean_what_they_say():
    with World(seed=4, sensor_noise=False, objects_per_scene=12) as world:
        scene = world.new_scene(np.random.default_rng(9))
        kitchen = world.kitchen
        x, y = scene.feature("location.x"), scene.feature("location.y")
        for place in INTEREST_POINTS:
            centre = kitchen.locations[place].centre
            assert scene.feature(f"location.{place}.dx") == pytest.approx(x - centre[0])
            assert scene.feature(f"location.{place}.distance") == pytest.approx(np.hypot(x - centre[0],
                                                                                          y - centre[1]))
        assert scene.feature("location.robot.distance") == pytest.approx(
            np.hypot(x - kitchen.robot_base[0], y - kitchen.robot_base[1]))
        assert scene.feature("location.robot.forward").min() > 0  # every object stands in front of the arm
        assert scene.feature("weight") == pytest.approx(np.array(scene.truth.masses))
        assert scene.feature("shape.box_volume") == pytest.approx(
            scene.feature("size.length") * scene.feature("size.width") * scene.feature("size.height"))
        assert np.all(scene.feature("shape.aspect_ratio") >= 1.0)
        for name in ("noise.max", "light.level"):
            assert np.all(scene.feature(name) == scene.feature(name)[0])  # one room per observation
        assert np.all(scene.feature("noise.min") <= scene.feature("noise.mean"))
        assert np.all(scene.feature("noise.mean") <= scene.feature("noise.max"))
        nearest = np.min([np.hypot(x - x[j], y - y[j]) + np.where(np.arange(len(x)) == j, 9, 0)
                          for j in range(len(x))], axis=0)
        assert scene.feature("location.nearest_neighbour") == pytest.approx(nearest)


def test_shape_features_separate_round_things_from_boxes():
    with World(seed=4, sensor_noise=False, objects_per_scene=40) as world:
        scene = world.new_scene(np.random.default_rng(2))
    kinds = np.array(scene.truth.kinds)
    round_things = np.isin(kinds, ["orange", "peach"])
    boxes = np.isin(kinds, ["pasta-box", "cracker-box", "microwave-meal", "juice-box"])
    assert round_things.any() and boxes.any()
    roundness, compactness = scene.feature("shape.roundness"), scene.feature("shape.compactness")
    assert roundness[round_things].min() > roundness[boxes].max()
    assert compactness[boxes].mean() > compactness[round_things].mean() + 0.2
    assert scene.feature("shape.top_drop")[round_things].mean() > scene.feature("shape.top_drop")[boxes].mean()


def test_texture_keypoints_differ_by_kind():
    with World(seed=6, sensor_noise=False, objects_per_scene=48) as world:
        kinds, keypoints = [], []
        for seed in range(2):
            scene = world.new_scene(np.random.default_rng(seed))
            kinds += list(scene.truth.kinds)
            keypoints += list(scene.feature("texture.keypoint_density"))
    kinds, keypoints = np.array(kinds), np.array(keypoints)
    busy = keypoints[np.isin(kinds, ["chip-bag", "pasta-box", "cracker-box"])]
    plain = keypoints[np.isin(kinds, ["peach", "orange"])]
    assert np.median(busy) > 3 * max(np.median(plain), 0.01)
