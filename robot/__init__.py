"""The 7-DOF Panda arm: inverse kinematics, proprioception and gestures."""

import bullet_world  # noqa: F401  (imports PyBullet first, without its banner)
from robot.arm import Arm, MotionResult

__all__ = ["Arm", "MotionResult"]
