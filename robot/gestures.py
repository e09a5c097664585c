"""Gestures that tell a person which object the robot means."""

from __future__ import annotations

import numpy as np

from robot.arm import Arm, MotionResult

POINTING_CLEARANCE_M = 0.08  # how far above the object's top the fingertip stops
TRAVEL_HEIGHT_M = 0.35       # height of the via point, clear of every object


def point_at(arm: Arm, position, top_height: float) -> MotionResult:
    """Move the fingertip above the object at ``position`` (its perceived centre).

    The arm first rises to a via point at travel height above the target, then
    descends to ``POINTING_CLEARANCE_M`` above the object's perceived top.
    """
    target = np.array([position[0], position[1], top_height + POINTING_CLEARANCE_M])
    via = np.array([position[0], position[1], max(TRAVEL_HEIGHT_M, target[2] + 0.1)])
    first = arm.move_fingertip_to(via, steps=180)
    final = arm.move_fingertip_to(target, steps=120)
    return MotionResult(final.reached, final.error_m, first.steps + final.steps, final.reason)
