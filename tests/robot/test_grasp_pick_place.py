"""Real pick-place with the Panda: objects end inside the region, failures come back with a reason."""

import numpy as np
import pybullet as p
import pytest

from bullet_world.catalogue import load_object_kinds
from bullet_world.perception import measure_objects
from bullet_world.world import World
from robot import Arm
from robot.grasping import GraspTarget, Obstacle
from robot.pick_place import FAILURE_REASONS, Manipulator

KINDS = {kind.name: kind for kind in load_object_kinds("serve-pasta")}


@pytest.fixture(scope="module")
def setup():
    world = World(task="serve-pasta", kitchen="kitchen-1", seed=0)
    arm = Arm(world)
    manipulator = Manipulator(arm)
    yield world, arm, manipulator
    manipulator.close()
    world.close()


@pytest.fixture
def clean(setup):
    world = setup[0]
    yield setup
    for body in list(world.object_bodies):
        world.remove_object(body)


def spawn(world, name: str, xy, yaw: float = 0.4, mass: float | None = None) -> int:
    draw = KINDS[name].sample(np.random.default_rng(5))
    if mass is not None:
        draw["mass"] = mass
    body = world.add_object(KINDS[name], xy, yaw, draw=draw)
    for _ in range(30):
        p.stepSimulation(physicsClientId=world.client)
    return body


def look(world, body: int) -> tuple[GraspTarget, list[Obstacle]]:
    images = world.render()
    measured = measure_objects(images.rgb, images.depth_buffer, images.segmentation, images.view_matrix,
                               images.projection_matrix, list(world.object_bodies))
    others = [Obstacle.from_measurement(m) for b, m in measured.items() if b != body and m is not None]
    return GraspTarget.from_measurement(measured[body]), others


def true_xy(world, body: int) -> np.ndarray:
    return np.array(p.getBasePositionAndOrientation(body, physicsClientId=world.client)[0][:2])


@pytest.mark.parametrize("name", ["large-red-bowl", "butter-dish", "tomato-sauce-jar"])
def test_objects_are_carried_into_the_region_and_stand_upright(clean, name):
    world, arm, manipulator = clean
    start, end = world.kitchen.locations["cupboard"], world.kitchen.locations["counter"]
    body = spawn(world, name, start.centre[:2])
    target, obstacles = look(world, body)
    place = np.asarray(end.centre[:2])
    result = manipulator.pick_place(target, place, end, obstacles)
    assert result.success and result.reason == "", result
    assert end.contains(true_xy(world, body))
    assert np.linalg.norm(true_xy(world, body) - place) < 0.01
    orientation = p.getBasePositionAndOrientation(body, physicsClientId=world.client)[1]
    assert np.array(p.getMatrixFromQuaternion(orientation))[8] > 0.95  # still upright
    assert 5.0 < result.sim_seconds < 20.0  # real simulated motion, within the step budget
    assert manipulator.gripper.held is None


def test_the_hand_turns_away_from_tall_neighbours(clean):
    """Two heavy kettles flank the pot along y; a hand whose fingers close along y hits them with its palm."""
    world, arm, manipulator = clean
    start, end = world.kitchen.locations["stove"], world.kitchen.locations["counter"]
    centre = np.asarray(start.centre[:2])
    outcomes = {}
    for use_obstacles in (False, True):
        body = spawn(world, "steel-pot", centre)
        for side in (-1, 1):
            spawn(world, "kettle", centre + [0.0, side * 0.075], mass=30.0)
        seen, obstacles = look(world, body)
        along_y = GraspTarget(seen.centre, seen.length, seen.width, seen.height, 0.0)  # first yaw: fingers along y
        result = manipulator.pick_place(along_y, end.centre[:2], end, obstacles if use_obstacles else ())
        outcomes[use_obstacles] = (result.success, end.contains(true_xy(world, body)))
        for leftover in list(world.object_bodies):
            world.remove_object(leftover)
    assert outcomes[True] == (True, True)
    assert outcomes[False] != (True, True)


def test_unreachable_place_fails_before_the_arm_moves(clean):
    world, arm, manipulator = clean
    body = spawn(world, "large-red-bowl", world.kitchen.locations["counter"].centre[:2])
    target, _ = look(world, body)
    before = arm.joint_positions()
    result = manipulator.pick_place(target, [1.6, 1.6])
    assert not result.success and result.reason == "ik-unreachable" and result.steps == 0
    assert np.allclose(arm.joint_positions(), before)


def test_nothing_there_is_a_missed_grasp(clean):
    world, arm, manipulator = clean
    ghost = GraspTarget((*world.kitchen.locations["counter"].centre[:2], 0.025), 0.06, 0.06, 0.05, 0.0)
    result = manipulator.pick_place(ghost, world.kitchen.locations["cupboard"].centre[:2])
    assert result.reason == "grasp-missed" and result.steps > 0 and result.held_body is None
    assert manipulator.gripper.held is None


def test_too_heavy_to_hold_is_a_drop(clean):
    world, arm, manipulator = clean
    body = spawn(world, "tomato-sauce-jar", world.kitchen.locations["counter"].centre[:2], mass=25.0)
    target, _ = look(world, body)
    result = manipulator.pick_place(target, world.kitchen.locations["cupboard"].centre[:2])
    assert result.reason == "dropped" and result.phase in ("lift", "carry")


def test_a_place_outside_the_region_is_reported(clean):
    world, arm, manipulator = clean
    counter, cupboard = world.kitchen.locations["counter"], world.kitchen.locations["cupboard"]
    body = spawn(world, "small-red-bowl", counter.centre[:2])
    target, _ = look(world, body)
    result = manipulator.pick_place(target, cupboard.centre[:2], region=world.kitchen.locations["stove"])
    assert result.reason == "placed-outside-region"
    assert cupboard.contains(result.placed_position[:2])  # the robot saw where it really is


def test_constraint_grasp_behind_the_same_interface(clean):
    world, arm, _ = clean
    manipulator = Manipulator(arm, mode="constraint")
    try:
        start, end = world.kitchen.locations["fridge"], world.kitchen.locations["counter"]
        body = spawn(world, "milk-carton", start.centre[:2])
        target, obstacles = look(world, body)
        result = manipulator.pick_place(target, end.centre[:2], end, obstacles)
        assert result.success, result
        assert p.getNumConstraints(physicsClientId=world.client) == 1  # only the finger coupling is left
    finally:
        manipulator.close()


def test_random_attempts_never_raise(clean):
    """A small version of ``scripts/bench_pick_place.py --random``: wrong perception, places anywhere."""
    world, arm, manipulator = clean
    rng = np.random.default_rng(17)
    names = list(KINDS)
    for _ in range(6):
        body = spawn(world, names[rng.integers(len(names))], world.kitchen.locations["counter"].centre[:2])
        target, _ = look(world, body)
        noisy = GraspTarget(tuple(np.asarray(target.centre) + rng.normal(0, 0.02, 3)),
                            target.length * rng.uniform(0.5, 2), target.width * rng.uniform(0.5, 2),
                            target.height * rng.uniform(0.5, 2), float(rng.uniform(-4, 4)))
        result = manipulator.pick_place(noisy, rng.uniform(-1.2, 1.2, 2), world.kitchen.locations["fridge"])
        assert result.reason in ("", *FAILURE_REASONS)
        assert manipulator.gripper.held is None
        for leftover in list(world.object_bodies):
            world.remove_object(leftover)
    bad = manipulator.pick_place(GraspTarget((np.nan, 0.0, 0.0), 0.05, 0.05, 0.05, 0.0), [0.0, 0.0])
    assert bad.reason == "invalid-target"
    assert manipulator.pick_place(GraspTarget((0, 0, 0.03), 0.05, 0.05, 0.05, 0.0), [np.inf, 0]).reason == \
        "invalid-target"
