"""prepare-lunch: objects change state over time, and only the features that should, move."""

import numpy as np
import pytest

from bullet_world import World

SURROUNDINGS = ("location.nearest_neighbour", "location.crowding")


@pytest.fixture(scope="module")
def lunch():
    with World(task="prepare-lunch", seed=3, sensor_noise=False) as world:
        yield world


def test_a_stage_puts_every_changing_object_in_that_state(lunch):
    scene = lunch.new_scene(np.random.default_rng(1), stage=0)
    expected = {"main dish": "boxed", "fruit": "whole", "snack": "as-is", "beverage": "as-is"}
    assert all(state == expected[c] for c, state in zip(scene.truth.concepts, scene.truth.states))
    scene = lunch.new_scene(np.random.default_rng(1), stage=5)
    expected = {"main dish": "in-bowl", "fruit": "sliced", "snack": "as-is", "beverage": "as-is"}
    assert all(state == expected[c] for c, state in zip(scene.truth.concepts, scene.truth.states))


def test_objects_stand_at_their_state_location(lunch):
    scene = lunch.new_scene(np.random.default_rng(2), stage=1)
    pots = [i for i, s in enumerate(scene.truth.states) if s == "in-pot"]
    stove = lunch.kitchen.locations["stove"]
    spill = 0.05  # a full stove lets a pot stand just beside it
    for i in pots:
        offset = np.abs(scene.truth.positions[i, :2] - np.asarray(stove.centre[:2]))
        assert np.all(offset <= np.asarray(stove.half_size) + spill + 1e-9)


def test_a_state_change_moves_the_features_it_should_and_not_the_others(lunch):
    before = lunch.new_scene(np.random.default_rng(4), stage=0)
    after = lunch.advance_states(np.random.default_rng(5), probability=1.0)
    names = list(before.feature_names)
    changed = np.array([c in ("main dish", "fruit") for c in before.truth.concepts])
    assert after.stage == before.stage + 1
    assert [s for s, c in zip(after.truth.states, changed) if c] == \
        ["in-pot" if c == "main dish" else "sliced" for c in np.array(before.truth.concepts)[changed]]
    assert after.truth.kinds == before.truth.kinds  # the same objects, in order

    steady = [i for i, n in enumerate(names) if n not in SURROUNDINGS]
    assert np.array_equal(before.X[~changed][:, steady], after.X[~changed][:, steady])
    room = [names.index(n) for n in ("noise.mean", "light.level")]
    assert np.array_equal(before.X[:, room], after.X[:, room])

    def moved(feature, rows=changed):
        column = names.index(feature)
        return np.abs(after.X[rows, column] - before.X[rows, column])

    pasta = np.array([c == "main dish" for c in before.truth.concepts])
    fruit = np.array([c == "fruit" for c in before.truth.concepts])
    assert np.all(moved("weight", pasta) > 0.3)          # a pot of pasta weighs more than its box
    assert np.all(moved("size.height", fruit) > 0.02)    # slices lie flat
    assert np.all(moved("location.x") + moved("location.y") > 0.05)   # carried to the stove or elsewhere
    appearance = moved("colour.red") + moved("colour.green") + moved("colour.blue") + moved("shape.top_drop")
    assert np.all(appearance > 0.02)


def test_no_change_when_nothing_advances(lunch):
    before = lunch.new_scene(np.random.default_rng(6), stage=0)
    after = lunch.advance_states(np.random.default_rng(7), probability=0.0)
    assert np.array_equal(before.X, after.X) and after.truth.states == before.truth.states


def test_the_last_state_stays(lunch):
    lunch.new_scene(np.random.default_rng(8), stage=2)
    states = lunch.scene.truth.states
    assert lunch.advance_states(np.random.default_rng(9), probability=1.0).truth.states == states
