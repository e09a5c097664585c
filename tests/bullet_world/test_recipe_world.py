"""Recipe scenes: households in their locations, the scripted teacher, observations, tracking."""

import numpy as np
import pytest

from bullet_world.recipes.setup import ELSEWHERE, load_recipe_setup
from bullet_world.recipes.tracking import match_rows
from bullet_world.recipes.world import RecipeWorld
from learning.recipes.grounding import Snapshot, parse_action

SALAD = [("bowl", "cupboard", "counter"), ("salad-dressing", "fridge", "counter")]


@pytest.fixture(scope="module")
def salad():
    """Seven demonstrations: the six arrangements of one sweep, then the first again in the evening."""
    with RecipeWorld(SALAD, task="serve-salad", kitchen="kitchen-1", seed=4) as world:
        demos = world.demonstrate(7, np.random.default_rng(8))
        yield world, demos


def test_every_object_starts_inside_its_location(salad):
    world, _ = salad
    for seed in range(3):
        world.arrange(world.new_arrangement(np.random.default_rng(seed)))
        for item, body in zip(world.household.objects, world.bodies):
            xy = world.true_position(body)[:2]
            if item.at == ELSEWHERE:
                assert not any(world.region(name).contains(xy) for name in ("cupboard", "fridge", "counter"))
            else:
                assert world.region(item.at).contains(xy), (item, xy)


def test_the_teacher_moves_each_step_object_into_the_end_location(salad):
    world, demos = salad
    for demo in demos:
        for step in demo.steps:
            row = step.after.truth.row_of_role(step.object)
            xy = world.to_world_frame(step.after.locations[row])[0, :2]
            assert world.region(step.end).contains(xy)


def test_rows_come_in_a_random_order_and_tracking_recovers_them(salad):
    world, demos = salad
    shuffled = 0
    for demo in demos:
        for step in demo.steps:
            before, after = step.before, step.after
            shuffled += before.truth.body_ids != world.bodies
            order = match_rows(before.appearance, before.locations, after.appearance, after.locations)
            assert [after.truth.body_ids[j] for j in order] == list(before.truth.body_ids)
    assert shuffled > 0


def test_the_moved_object_is_found_from_perceived_features(salad):
    _, demos = salad
    for demo in demos:
        for step in demo.steps:
            order = match_rows(step.before.appearance, step.before.locations, step.after.appearance,
                               step.after.locations)
            action = parse_action(Snapshot(step.before.appearance, step.before.locations),
                                  Snapshot(step.after.appearance[order], step.after.locations[order]))
            assert step.before.truth.roles[action.moved_index] == step.object
            assert action.change > 0.1


def test_same_arrangement_under_the_second_lighting_changes_colour_not_place(salad):
    world, demos = salad
    first, again = demos[0], demos[6]
    assert first.layout == again.layout and (first.lighting, again.lighting) == ("daylight", "evening")
    a, b = first.steps[0].before, again.steps[0].before
    rows_b = [b.truth.body_ids.index(body) for body in a.truth.body_ids]
    assert np.abs(a.locations - b.locations[rows_b]).max() < 0.01
    assert np.abs(a.appearance[:, :3] - b.appearance[rows_b, :3]).mean() > 0.05


def test_the_sweep_changes_a_little_each_time_and_a_lot_over_the_series(salad):
    world, demos = salad
    spots = np.array([demo.steps[0].before.locations[demo.steps[0].before.truth.row_of_role("bowl")]
                      for demo in demos[:6]])[:, :2]
    adjacent = np.linalg.norm(np.diff(spots, axis=0), axis=1).mean()
    overall = max(np.linalg.norm(spots[i] - spots[j]) for i in range(6) for j in range(6))
    assert adjacent < overall / 1.5
    region = world.region("cupboard")
    assert overall > 0.5 * min(region.half_size)


def test_same_seed_same_demonstrations():
    runs = []
    for _ in range(2):
        with RecipeWorld(SALAD, task="serve-salad", kitchen="kitchen-2", seed=1) as world:
            runs.append(world.demonstrate(1, np.random.default_rng(2))[0])
    for first, second in zip(runs[0].steps, runs[1].steps):
        assert np.array_equal(first.before.appearance, second.before.appearance)
        assert np.array_equal(first.after.locations, second.after.locations)


def test_robot_frame_round_trip(salad):
    world, _ = salad
    points = np.array([[0.1, 0.2, 0.03], [-0.3, 0.05, 0.1]])
    assert np.allclose(world.to_world_frame(world.to_robot_frame(points)), points)
    base = np.asarray(world.kitchen.robot_base)
    assert np.allclose(world.to_robot_frame(base[None])[0], 0.0)


def test_tracking_keeps_a_look_alike_that_did_not_move():
    """Two identical bowls; the first moves 40 cm. Swapping them must never look cheaper (module doc)."""
    rng = np.random.default_rng(0)
    appearance = np.array([[0.8, 0.1, 0.1, 0.06, 0.06, 0.05]] * 2 + [[0.1, 0.1, 0.8, 0.04, 0.04, 0.1]])
    before = np.array([[0.5, 0.0, 0.02], [0.3, 0.1, 0.02], [0.6, 0.3, 0.05]])
    after = before.copy()
    after[0, :2] += [-0.3, -0.25]
    for _ in range(20):
        order = rng.permutation(3)
        noisy = appearance[order] + rng.normal(0, 0.005, (3, 6))
        found = match_rows(appearance, before, noisy, after[order])
        assert list(order[found]) == [0, 1, 2]


def test_tracking_rejects_different_object_counts():
    with pytest.raises(ValueError, match="cannot match 2 objects before with 1 after"):
        match_rows(np.zeros((2, 6)), np.zeros((2, 3)), np.zeros((1, 6)), np.zeros((1, 3)))


def test_recipe_that_the_household_cannot_serve_is_rejected():
    with pytest.raises(ValueError, match="has no object playing 'teapot'"):
        RecipeWorld([("teapot", "stove", "counter")], task="serve-salad", kitchen="kitchen-1")
    with pytest.raises(ValueError, match="lives at 'cupboard', but the recipe takes it from 'stove'"):
        RecipeWorld([("bowl", "stove", "counter")], task="serve-salad", kitchen="kitchen-1")


BASE_TASK = """name = "tiny"
concepts = ["bowl", "salad-dressing", "distractor"]
objects = "serve-salad"
objects_per_scene = 3
test_scenes = 1
"""
SCENES = """
[recipe_scenes]
recipe = "serve-salad"
reach = [0.3, 0.76]
region_margin = 0.01
min_gap = 0.02
layouts = 2
jitter_m = 0.01
yaw_jitter = 0.2
settle_steps = 10
lighting.day = { direction = [0, 0, 1], ambient = 0.6, diffuse = 0.5 }
[[recipe_scenes.household]]
name = "h"
kitchens = ["kitchen-1"]
objects = [{ kind = "blue-bowl", role = "bowl", at = "cupboard" }]
"""


@pytest.mark.parametrize("change, message", [
    (("", ""), None),
    (('reach = [0.3, 0.76]', 'reach = [0.8, 0.3]'), "'reach' must be \\[near, far\\]"),
    (('kind = "blue-bowl"', 'kind = "teapot"'), "unknown kind 'teapot'; the task's object file has: "),
    (('layouts = 2', 'layouts = 0'), "'layouts' must be >= 1"),
    (('ambient = 0.6', 'ambient = 1.6'), "'ambient' and 'diffuse' must lie in \\[0, 1\\]"),
    (('jitter_m = 0.01', 'wobble = 0.01'), "unknown field 'wobble'"),
    (('role = "bowl", at', 'role = "bowl", colour = "red", at'), "unknown field 'colour'; accepted: kind, role, at"),
])
def test_scene_setup_file_errors_name_the_field(tmp_path, change, message):
    path = tmp_path / "tiny.toml"
    path.write_text(BASE_TASK + SCENES.replace(*change))
    if message is None:
        setup = load_recipe_setup(path)
        assert setup.household_for("kitchen-9").name == "h" and setup.lighting["day"].direction == (0, 0, 1)
    else:
        with pytest.raises(ValueError, match=message):
            load_recipe_setup(path)


def test_a_task_without_recipe_scenes_says_so(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(BASE_TASK)
    with pytest.raises(ValueError, match="has no \\[recipe_scenes\\] table; it is not a recipe task"):
        load_recipe_setup(path)
