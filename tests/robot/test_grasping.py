"""Grasp geometry and reachability: which way the fingers close, hand clearance, IK on the twin."""

import numpy as np
import pybullet as p
import pytest

from bullet_world.world import World
from robot import Arm
from robot.arm import FINGER_JOINTS
from robot.grasping import (
    MAX_GRASP_WIDTH_M,
    GraspTarget,
    Gripper,
    Obstacle,
    couple_fingers,
    hand_clearance,
)
from robot.kinematics import KinematicTwin


@pytest.fixture(scope="module")
def panda():
    world = World(task="serve-pasta", kitchen="kitchen-1", seed=0)
    arm = Arm(world)
    twin = KinematicTwin(arm)
    yield world, arm, twin
    twin.close()
    world.close()


def finger_axis(twin: KinematicTwin, joints: np.ndarray) -> np.ndarray:
    """Unit vector from one fingertip to the other, by forward kinematics on the twin (fingers open)."""
    for finger in FINGER_JOINTS:
        p.resetJointState(twin.body_id, finger, 0.04, physicsClientId=twin.client)
    twin.fingertip_pose(joints)
    first, second = (np.array(p.getLinkState(twin.body_id, link, physicsClientId=twin.client)[4])
                     for link in FINGER_JOINTS)
    axis = (first - second)[:2]
    return axis / np.linalg.norm(axis)


@pytest.mark.parametrize("object_yaw", [0.0, 0.6, 1.4, 2.5])
def test_fingers_close_across_the_width_of_a_box(panda, object_yaw):
    _, arm, twin = panda
    target = GraspTarget((0.1, 0.0, 0.03), 0.09, 0.05, 0.06, object_yaw)
    long_side = np.array([np.cos(object_yaw), np.sin(object_yaw)])
    for yaw in target.hand_yaws():
        solution = twin.solve([0.1, 0.0, target.grasp_tip_height()], yaw, (arm.joint_positions(),))
        assert solution.reachable
        assert abs(finger_axis(twin, solution.joints) @ long_side) < 0.02  # perpendicular to the long side


def test_twin_solutions_stay_within_joint_limits_and_report_unreachable_points(panda):
    _, arm, twin = panda
    near = twin.solve([0.0, 0.1, 0.05], 0.3, (arm.joint_positions(),))
    assert near.reachable and near.position_error_m < 0.005
    assert np.all(near.joints >= twin.lower) and np.all(near.joints <= twin.upper)
    far = twin.solve([1.5, 1.5, 0.05], 0.3)
    assert not far.reachable and far.position_error_m > 0.3


def test_targets_that_cannot_be_grasped_say_why():
    assert GraspTarget((0, 0, 0.03), 0.1, MAX_GRASP_WIDTH_M + 0.005, 0.06, 0.0).problem() == "too-wide-for-gripper"
    assert GraspTarget((0, 0, np.nan), 0.05, 0.05, 0.06, 0.0).problem() == "invalid-target"
    assert GraspTarget((0, 0, 0.03), 0.05, 0.0, 0.06, 0.0).problem() == "invalid-target"
    assert GraspTarget((0, 0, 0.03), 0.05, 0.05, 0.06, 0.0).problem() == ""


def test_grasp_height_keeps_the_pads_off_the_counter_and_the_palm_above_the_top():
    flat = GraspTarget((0, 0, 0.01), 0.06, 0.06, 0.02, 0.0)
    tall = GraspTarget((0, 0, 0.07), 0.04, 0.04, 0.14, 0.0)
    assert flat.grasp_tip_height() > 0.012
    assert tall.top - 0.035 < tall.grasp_tip_height() < tall.top


def test_round_objects_offer_many_hand_yaws_boxes_two():
    assert len(GraspTarget((0, 0, 0.03), 0.064, 0.062, 0.05, 0.3).candidate_hand_yaws()) == 12
    assert len(GraspTarget((0, 0, 0.03), 0.09, 0.05, 0.05, 0.3).candidate_hand_yaws()) == 2


def test_hand_clearance_sees_tall_neighbours_along_the_fingers_only():
    tall, short = 0.15, 0.02
    # hand yaw 0: the fingers close along world y (yaw minus a quarter turn)
    along_y = Obstacle((0.0, 0.09), 0.03, tall)
    along_x = Obstacle((0.09, 0.0), 0.03, tall)
    assert hand_clearance((0.0, 0.0), 0.0, 0.05, [along_y]) < 0
    assert hand_clearance((0.0, 0.0), 0.0, 0.05, [along_x]) > 0
    assert hand_clearance((0.0, 0.0), 0.0, 0.05, [Obstacle((0.0, 0.09), 0.03, short)]) > 0
    assert hand_clearance((0.0, 0.0), np.pi / 2, 0.05, [along_y]) > 0
    assert hand_clearance((0.0, 0.0), 0.0, 0.05, []) == np.inf


def test_fingers_are_coupled_once_and_move_together(panda):
    world, arm, _ = panda
    first = couple_fingers(arm)
    assert couple_fingers(arm) == first
    gripper = Gripper(arm)
    gripper.open()
    gripper.close()  # nothing between the fingers
    assert gripper.held is None and gripper.last_steps <= 120
    opening = [state[0] for state in p.getJointStates(arm.body_id, FINGER_JOINTS, physicsClientId=world.client)]
    assert abs(opening[0] - opening[1]) < 0.002


def test_unknown_grasp_mode_is_rejected_with_the_accepted_ones(panda):
    _, arm, _ = panda
    with pytest.raises(ValueError, match="accepted: friction, constraint"):
        Gripper(arm, mode="magnet")
