"""Gestures that tell a person which object the robot means.

``point_at`` plans on a kinematic copy of the arm (``robot.kinematics``) before
the real arm moves: the fingertip should end straight above the object,
``POINTING_CLEARANCE_M`` over its perceived top. Where the arm cannot point
straight down from there (an object far to the side), it points from higher up
(up to ``MAX_CLEARANCE_M``), still straight above the object; only if no such
pose exists does it take the best pose it found, and the result says so.
The motion itself runs in the physics simulation: up and over at travel height,
then down.
"""

from __future__ import annotations

import weakref

import numpy as np

from robot.arm import SIM_STEP_SECONDS, Arm, MotionResult
from robot.kinematics import IkSolution, KinematicTwin

POINTING_CLEARANCE_M = 0.08  # how far above the object's top the fingertip stops
MAX_CLEARANCE_M = 0.26       # the highest a pointing pose may be, for objects at the edge of reach
CLEARANCE_STEP_M = 0.06
TRAVEL_HEIGHT_M = 0.35       # height of the via point, clear of every object
HORIZONTAL_TOLERANCE_M = 0.02  # a pointing gesture counts as reached within this of the object's centre
VIA_STEPS, FINAL_STEPS = 120, 80  # 0.83 s of simulated motion in all: a brisk, readable gesture

_twins: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def twin_of(arm: Arm) -> KinematicTwin:
    """The arm's kinematic copy (made once per arm)."""
    if arm not in _twins:
        _twins[arm] = KinematicTwin(arm)
    return _twins[arm]


def _yaws(arm: Arm, position) -> tuple[float, ...]:
    """Hand yaws worth trying: along the line from the base to the object, across it, and the default."""
    offset = np.asarray(position[:2], dtype=float) - np.asarray(arm.base_position[:2], dtype=float)
    heading = float(np.arctan2(offset[1], offset[0]))
    return (0.0, heading, heading + np.pi / 2)


def plan_pointing(arm: Arm, position, top_height: float) -> tuple[IkSolution, float]:
    """Joint angles that put the fingertip straight above ``position`` (lowest clearance that works)."""
    twin = twin_of(arm)
    seeds = (arm.joint_positions(),)
    best: tuple[IkSolution, float] | None = None
    clearance = POINTING_CLEARANCE_M
    while clearance <= MAX_CLEARANCE_M + 1e-9:
        target = np.array([position[0], position[1], top_height + clearance])
        for yaw in _yaws(arm, position):
            solution = twin.solve(target, yaw, seeds)
            if solution.reachable:
                return solution, clearance
            if best is None or solution.position_error_m < best[0].position_error_m:
                best = (solution, clearance)
        clearance += CLEARANCE_STEP_M
    return best


def plan_via(arm: Arm, position, final: IkSolution, height: float) -> IkSolution | None:
    """A reachable pose above the target at travel height (lower if need be); None: go straight."""
    twin = twin_of(arm)
    via_height = max(TRAVEL_HEIGHT_M, height + 0.1)
    while via_height >= height + 0.05:
        target = np.array([position[0], position[1], via_height])
        solution = twin.solve(target, twin.hand_yaw(final.joints), (final.joints, arm.joint_positions()))
        if solution.reachable:
            return solution
        via_height -= 0.07
    return None


def paced_steps(start, target, steps: int, joint_speed: float | None) -> int:
    """Simulation steps for a cosine-profiled joint motion from ``start`` to ``target``.

    ``joint_speed`` None: ``steps`` whatever the distance (the fixed-length gesture). Otherwise no joint may
    exceed ``joint_speed`` rad/s: the profile's peak speed is pi/2 x |dq| / duration, so the motion lasts at
    least pi/2 x max|dq| / joint_speed seconds (never less than ``steps``): a far reach takes longer.
    """
    if joint_speed is None:
        return steps
    if not joint_speed > 0:
        raise ValueError(f"joint_speed must be a positive number of rad/s, got {joint_speed!r}")
    largest = float(np.max(np.abs(np.asarray(target, dtype=float) - np.asarray(start, dtype=float))))
    return max(steps, int(np.ceil(np.pi / 2 * largest / joint_speed / SIM_STEP_SECONDS)))


def point_at(arm: Arm, position, top_height: float, joint_speed: float | None = None) -> MotionResult:
    """Move the fingertip straight above the object at ``position`` (its perceived centre).

    ``reached`` means the fingertip ended within ``HORIZONTAL_TOLERANCE_M`` of the
    object's centre seen from above, at most ``MAX_CLEARANCE_M`` over its top.
    ``joint_speed`` (rad/s, None: the fixed-length gesture) paces the motion by the
    arm's joint-speed limit (:func:`paced_steps`), as embodied query costs need.
    """
    final, clearance = plan_pointing(arm, position, top_height)
    via = plan_via(arm, position, final, top_height + clearance)
    steps = 0
    if via is not None:
        steps += arm.move_to_joints(via.joints,
                                    steps=paced_steps(arm.joint_positions(), via.joints, VIA_STEPS, joint_speed)).steps
    motion = arm.move_to_joints(final.joints,
                                steps=paced_steps(arm.joint_positions(), final.joints, FINAL_STEPS, joint_speed))
    steps += motion.steps
    tip = arm.fingertip_position()
    horizontal = float(np.hypot(tip[0] - position[0], tip[1] - position[1]))
    height = float(tip[2] - top_height)
    reached = horizontal <= HORIZONTAL_TOLERANCE_M and 0.0 < height <= MAX_CLEARANCE_M + 0.02
    reason = "" if reached else f"fingertip {horizontal:.3f} m beside and {height:.3f} m above the object"
    return MotionResult(reached, horizontal, steps, reason)
