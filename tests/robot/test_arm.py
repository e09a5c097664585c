"""The Panda really moves: IK within limits, pointing ends above the object meant."""

import numpy as np

from robot.gestures import POINTING_CLEARANCE_M


def test_pointing_puts_the_fingertip_above_each_object(kitchen):
    scene = kitchen.next_scene(np.random.default_rng(21))
    for index in range(0, scene.n_objects, 3):
        report = kitchen.point_at(scene, index)
        tip = kitchen.arm.fingertip_position()
        true_top = scene.truth.positions[index, 2] + scene.truth.sizes[index, 2] / 2
        assert report["reached"], report
        assert report["horizontal_error_m"] < 0.02
        assert true_top < tip[2] < true_top + POINTING_CLEARANCE_M + 0.03


def test_motion_takes_simulated_time_and_respects_joint_limits(kitchen):
    arm = kitchen.arm
    start = arm.joint_positions()
    result = arm.move_fingertip_to([0.2, 0.1, 0.3])
    assert result.reached and result.steps > 100
    joints = arm.joint_positions()
    assert np.all(joints >= arm.lower - 1e-3) and np.all(joints <= arm.upper + 1e-3)
    assert not np.allclose(joints, start)


def test_unreachable_target_is_reported_not_raised(kitchen):
    result = kitchen.arm.move_fingertip_to([2.0, 2.0, 0.3])
    assert not result.reached and result.reason == "target out of reach"


def test_proprioception_names_match_values(kitchen):
    values = kitchen.arm.proprioception()
    robot_names = tuple(name for name in kitchen.feature_names if name.startswith(("arm.", "hand.")))
    assert tuple(values) == robot_names
    assert all(np.isfinite(v) for v in values.values())
