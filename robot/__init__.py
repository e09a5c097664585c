"""The 7-DOF Panda arm: inverse kinematics, proprioception and gestures."""

from robot.arm import Arm, MotionResult

__all__ = ["Arm", "MotionResult"]
