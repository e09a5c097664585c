"""Grasping with the Panda's two fingers: what to grasp, how, and whether the hand holds it.

A ``GraspTarget`` is what perception reports about an object: the centre of its
bounding box, its footprint length and width, its height and the yaw of its long
side (``bullet_world.perception.ObjectMeasurement``). The hand comes from above,
pointing straight down, with the fingers closing across the footprint's *width*.
The Panda opens to 8 cm, so an object is graspable when its width leaves a
margin on both sides (``MAX_GRASP_WIDTH_M``).

Two grasp modes sit behind one ``Gripper`` interface:

* ``"friction"`` (default): the finger motors squeeze with their force limit and
  friction alone carries the object. While holding, every motion keeps
  commanding the fingers closed.
* ``"constraint"``: the fingers first close on the object exactly as above and
  the grasp only counts if both fingers touch it; then a fixed
  ``pybullet.createConstraint`` joins the object to the hand in its current
  relative pose, as a stand-in for a firm grip. Releasing removes the
  constraint before opening the fingers. The constraint never creates a grasp
  the fingers did not make; it only rules out slip during fast motions.

Coupled fingers. The Panda's two fingers are driven together by one motor;
the URDF declares them as two independent joints (the mimic tag is ignored by
PyBullet), and two independently squeezing fingers let a held object slide
along the finger axis whenever the arm accelerates. The gripper couples them
with a gear constraint (ratio -1) once, so they open and close as one.

Whether the hand holds something is sensed, not looked up: the hand holds the
body that both fingers touch (PyBullet contact points, the simulated analogue
of finger contact sensors). Every wait counts simulation steps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

from learning.errors import SettingsError
from robot.arm import FINGER_JOINTS, HAND_LINK, Arm, MotionResult

MAX_OPENING_M = 0.08            # the Panda's full finger opening
GRASP_MARGIN_M = 0.006          # free space wanted on each side of the object when the hand opens
MAX_GRASP_WIDTH_M = MAX_OPENING_M - 2 * GRASP_MARGIN_M
FINGER_BELOW_TIP_M = 0.012      # the finger pads reach this far below the fingertip frame
HAND_ABOVE_TIP_M = 0.035        # the palm is this far above the fingertip frame
GRASP_DEPTH_M = 0.028           # how far below the object's top the fingertip frame goes
MIN_TIP_HEIGHT_M = FINGER_BELOW_TIP_M + 0.004  # keeps the pads off the surface
HAND_HALF_LENGTH_M = 0.105      # the hand reaches this far either way along the finger axis (palm)
HAND_HALF_WIDTH_M = 0.035       # ... and this far across it
FINGER_HALF_LENGTH_M = 0.052    # open fingers: outer faces along the finger axis
FINGER_HALF_WIDTH_M = 0.012
ROUND_TOLERANCE = 0.12          # a footprint whose sides differ by less than this fraction is round
YAW_CHOICES = 12                # hand yaws tried around a round object
CLOSE_STEPS = 120               # simulation steps allowed for the fingers to close
FINGER_COUPLING_FORCE = 50.0    # newtons the gear constraint may use to keep the fingers symmetric
OPEN_STEPS = 60
FINGER_CHECK_STEPS = 10         # how often closing fingers are checked for having stopped
FRICTION = "friction"
CONSTRAINT = "constraint"
GRASP_MODES = (FRICTION, CONSTRAINT)


@dataclass(frozen=True)
class GraspTarget:
    """A perceived object to grasp: bounding-box centre (x, y, z), footprint, height, yaw of the long side."""

    centre: tuple[float, float, float]
    length: float
    width: float
    height: float
    yaw: float

    @classmethod
    def from_measurement(cls, measurement) -> GraspTarget:
        """Build from a ``bullet_world.perception.ObjectMeasurement``."""
        return cls(tuple(float(v) for v in measurement.centroid), float(measurement.length),
                   float(measurement.width), float(measurement.height), float(measurement.yaw))

    def problem(self) -> str:
        """Why this target cannot be grasped at all ("" when it can be tried)."""
        numbers = (*self.centre, self.length, self.width, self.height, self.yaw)
        if len(self.centre) != 3 or not all(np.isfinite(v) for v in numbers):
            return "invalid-target"
        if min(self.length, self.width, self.height) <= 0:
            return "invalid-target"
        if self.width > MAX_GRASP_WIDTH_M:
            return "too-wide-for-gripper"
        return ""

    @property
    def bottom(self) -> float:
        return self.centre[2] - self.height / 2

    @property
    def top(self) -> float:
        return self.centre[2] + self.height / 2

    def grasp_tip_height(self) -> float:
        """Height of the fingertip frame when the fingers close on the object."""
        depth = min(GRASP_DEPTH_M, 0.6 * self.height)
        return max(self.top - depth, self.bottom + MIN_TIP_HEIGHT_M)

    @property
    def is_round(self) -> bool:
        return self.length - self.width <= ROUND_TOLERANCE * self.length

    def candidate_hand_yaws(self) -> list[float]:
        """Hand yaws that close the fingers across the object: any for a round footprint, else across
        the width (each as the pair half a turn apart, which IK may need for the last joint's limits)."""
        if not self.is_round:
            return list(self.hand_yaws())
        yaws = []
        for k in range(YAW_CHOICES // 2):
            yaws.extend(GraspTarget(self.centre, self.length, self.width, self.height,
                                    self.yaw + k * np.pi / (YAW_CHOICES // 2)).hand_yaws())
        return yaws

    def hand_yaws(self) -> tuple[float, float]:
        """The two hand yaws (half a turn apart) that close the fingers across the width."""
        # The fingers close along the hand's yaw minus a quarter turn, so a hand yaw equal to
        # the long side's yaw (modulo half a turn) closes them across the width.
        first = float(np.mod(self.yaw + np.pi, 2 * np.pi) - np.pi)  # in [-pi, pi)
        second = first + np.pi if first < 0 else first - np.pi
        return first, second


@dataclass(frozen=True)
class Obstacle:
    """Another perceived object near the hand: centre (x, y), radius of its footprint, top height."""

    centre: tuple[float, float]
    radius: float
    top: float

    @classmethod
    def from_measurement(cls, measurement) -> Obstacle:
        return cls((float(measurement.centroid[0]), float(measurement.centroid[1])),
                   0.5 * float(np.hypot(measurement.length, measurement.width)), float(measurement.height))


def hand_clearance(xy, yaw: float, tip_z: float, obstacles) -> float:
    """Smallest gap (m) between the hand at ``xy``, ``yaw``, fingertip height ``tip_z`` and the obstacles.

    The palm is a rectangle along the finger axis that matters for obstacles taller than its underside;
    the open fingers are a smaller rectangle that matters for obstacles taller than the pads' lower
    edge. Negative means a collision; +inf when nothing is near.
    """
    axis_angle = yaw - np.pi / 2  # the fingers close along the hand's yaw minus a quarter turn
    along = np.array([np.cos(axis_angle), np.sin(axis_angle)])
    across = np.array([-along[1], along[0]])
    gap = np.inf
    for obstacle in obstacles:
        offset = np.asarray(obstacle.centre, dtype=float) - np.asarray(xy, dtype=float)[:2]
        local = np.abs([offset @ along, offset @ across])
        for half, floor in (((HAND_HALF_LENGTH_M, HAND_HALF_WIDTH_M), tip_z + HAND_ABOVE_TIP_M),
                            ((FINGER_HALF_LENGTH_M, FINGER_HALF_WIDTH_M), tip_z - FINGER_BELOW_TIP_M)):
            if obstacle.top > floor:
                outside = np.maximum(local - np.asarray(half), 0.0)
                gap = min(gap, float(np.hypot(*outside)) - obstacle.radius)
    return gap


def finger_contacts(arm: Arm) -> dict[int, set[int]]:
    """Which bodies each finger touches: body id -> set of finger joints in contact."""
    touching: dict[int, set[int]] = {}
    for finger in FINGER_JOINTS:
        for contact in p.getContactPoints(bodyA=arm.body_id, linkIndexA=finger, physicsClientId=arm.client):
            if contact[2] != arm.body_id:
                touching.setdefault(int(contact[2]), set()).add(finger)
    return touching


def body_between_fingers(arm: Arm, ignore: tuple[int, ...] = ()) -> int | None:
    """The body both fingers touch, or None (the simulated finger contact sensors)."""
    both = [body for body, fingers in finger_contacts(arm).items() if len(fingers) == 2 and body not in ignore]
    return both[0] if len(both) == 1 else None


def couple_fingers(arm: Arm) -> int:
    """Make the two finger joints move as one (see the module doc); returns the gear constraint's id,
    creating it only if the arm does not have it yet."""
    first, second = FINGER_JOINTS
    for index in range(p.getNumConstraints(physicsClientId=arm.client)):
        uid = p.getConstraintUniqueId(index, physicsClientId=arm.client)
        info = p.getConstraintInfo(uid, physicsClientId=arm.client)
        if info[:5] == (arm.body_id, first, arm.body_id, second, p.JOINT_GEAR):
            return uid
    gear = p.createConstraint(arm.body_id, first, arm.body_id, second, p.JOINT_GEAR, [1, 0, 0], [0, 0, 0],
                              [0, 0, 0], physicsClientId=arm.client)
    p.changeConstraint(gear, gearRatio=-1, erp=0.1, maxForce=FINGER_COUPLING_FORCE, physicsClientId=arm.client)
    return gear


class Gripper:
    """Open, close, hold and release, in either grasp mode (see the module docstring)."""

    def __init__(self, arm: Arm, mode: str = FRICTION, ignore_bodies: tuple[int, ...] = ()):
        if mode not in GRASP_MODES:
            raise SettingsError(f"unknown grasp mode {mode!r}; accepted: {', '.join(GRASP_MODES)}")
        self.arm = arm
        couple_fingers(arm)
        self.mode = mode
        self.ignore_bodies = tuple(ignore_bodies)
        self.held: int | None = None
        self.last_steps = 0  # simulation steps used by the latest open() or close()
        self._constraint: int | None = None

    @property
    def command(self) -> float:
        """The finger opening every arm motion must command: squeeze while holding or closed."""
        return 0.0 if self.held is not None else MAX_OPENING_M

    def open(self, steps: int = OPEN_STEPS) -> MotionResult:
        """Release whatever is held and open the fingers fully, holding the arm still."""
        if self._constraint is not None:
            p.removeConstraint(self._constraint, physicsClientId=self.arm.client)
            self._constraint = None
        self.held = None
        motion = self._fingers_to(MAX_OPENING_M, steps)
        self.last_steps = motion.steps
        return motion

    def close(self, steps: int = CLOSE_STEPS) -> int | None:
        """Close the fingers on whatever is between them; return the held body or None."""
        self.last_steps = self._fingers_to(0.0, steps, stop_on_contact=True).steps
        body = body_between_fingers(self.arm, self.ignore_bodies)
        if body is None:
            self.held = None
            return None
        self.held = body
        if self.mode == CONSTRAINT:
            self._constraint = self._attach(body)
        return body

    def still_holding(self) -> bool:
        """True while both fingers still touch the held body (the constraint counts as a grip)."""
        if self.held is None:
            return False
        if self._constraint is not None:
            return True
        return body_between_fingers(self.arm, self.ignore_bodies) == self.held

    def _fingers_to(self, opening: float, steps: int, stop_on_contact: bool = False) -> MotionResult:
        """Drive only the fingers for up to ``steps`` simulation steps; the arm holds its joints."""
        joints = self.arm.joint_positions()
        used = 0
        while used < steps:
            chunk = min(FINGER_CHECK_STEPS, steps - used)
            self.arm.move_to_joints(joints, opening=opening, steps=chunk, settle_steps=0)
            used += chunk
            if stop_on_contact and used >= 2 * FINGER_CHECK_STEPS and self._fingers_settled():
                break
        error = abs(self.arm.finger_opening() - opening)
        return MotionResult(True, error, used)

    def _fingers_settled(self) -> bool:
        states = p.getJointStates(self.arm.body_id, FINGER_JOINTS, physicsClientId=self.arm.client)
        return all(abs(state[1]) < 1e-3 for state in states)

    def _attach(self, body: int) -> int:
        """Fix ``body`` to the hand in its current relative pose."""
        client = self.arm.client
        hand = p.getLinkState(self.arm.body_id, HAND_LINK, computeForwardKinematics=True, physicsClientId=client)
        hand_position, hand_orientation = hand[0], hand[1]  # constraint frames are relative to the link's COM
        body_position, body_orientation = p.getBasePositionAndOrientation(body, physicsClientId=client)
        inverse_position, inverse_orientation = p.invertTransform(hand_position, hand_orientation)
        relative_position, relative_orientation = p.multiplyTransforms(inverse_position, inverse_orientation,
                                                                       body_position, body_orientation)
        constraint = p.createConstraint(self.arm.body_id, HAND_LINK, body, -1, p.JOINT_FIXED, [0, 0, 0],
                                        relative_position, [0, 0, 0], relative_orientation,
                                        physicsClientId=client)
        p.changeConstraint(constraint, maxForce=200.0, physicsClientId=client)
        return constraint
