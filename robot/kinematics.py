"""Reachability checks on a kinematic copy of the arm, so a plan is verified before the arm moves.

``pybullet.calculateInverseKinematics`` returns an answer even for targets the
arm cannot reach, and that answer depends on the joint state it starts from. A
``KinematicTwin`` is a second, never-stepped PyBullet client holding the same
Panda at the same base pose: a candidate joint vector is written into the twin,
its fingertip pose read back by forward kinematics, and the position and
pointing errors compared with a tolerance. The real world is never touched, so
checking a plan costs no simulated time and disturbs no contact.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import pybullet as p
import pybullet_data

from robot.arm import ARM_JOINTS, FINGERTIP_LINK, REST_JOINTS

POSITION_TOLERANCE_M = 0.005     # fingertip position error accepted for a solution
POINTING_TOLERANCE_RAD = 0.05    # angle between the hand's approach axis and straight down
IK_REFINEMENTS = 6               # re-seeded IK calls per starting pose
# The Panda's "ready" pose (hand forward and down): the null-space IK is pulled towards it.
READY_JOINTS = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


@dataclass(frozen=True)
class IkSolution:
    """Joint angles within limits and how well they reach the requested pose."""

    joints: np.ndarray
    position_error_m: float
    pointing_error_rad: float

    @property
    def reachable(self) -> bool:
        return self.position_error_m <= POSITION_TOLERANCE_M and self.pointing_error_rad <= POINTING_TOLERANCE_RAD


class KinematicTwin:
    """A copy of the arm in its own DIRECT client, used only for kinematics."""

    def __init__(self, arm):
        self.client = p.connect(p.DIRECT)
        self._finalizer = weakref.finalize(self, _disconnect, self.client)
        self.body_id = p.loadURDF(pybullet_data.getDataPath() + "/franka_panda/panda.urdf",
                                  list(map(float, arm.base_position)), arm.base_orientation, useFixedBase=True,
                                  physicsClientId=self.client)
        self.base_position = np.asarray(arm.base_position, dtype=float)
        self.base_yaw = float(p.getEulerFromQuaternion(arm.base_orientation)[2])
        self.lower = np.asarray(arm.lower, dtype=float)
        self.upper = np.asarray(arm.upper, dtype=float)

    def close(self) -> None:
        self._finalizer()

    def fingertip_pose(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: fingertip position and the hand's approach axis (unit vector)."""
        for joint, angle in zip(ARM_JOINTS, joints):
            p.resetJointState(self.body_id, joint, float(angle), physicsClientId=self.client)
        state = p.getLinkState(self.body_id, FINGERTIP_LINK, computeForwardKinematics=True,
                               physicsClientId=self.client)
        rotation = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        return np.array(state[4]), rotation[:, 2]

    def _ready_facing(self, target: np.ndarray) -> tuple[np.ndarray, ...]:
        """The ready pose with the first joint turned towards the target, elbow as is, more and less bent."""
        offset = np.asarray(target[:2], dtype=float) - self.base_position[:2]
        heading = float(np.arctan2(offset[1], offset[0])) - self.base_yaw
        seeds = []
        for elbow_change in (0.0, -0.5, 0.6):
            seed = READY_JOINTS.copy()
            seed[0] = float(np.mod(heading + np.pi, 2 * np.pi) - np.pi)
            seed[3] += elbow_change
            seed[5] -= elbow_change
            seeds.append(seed)
        return tuple(seeds)

    def hand_yaw(self, joints: np.ndarray) -> float:
        """Rotation of the hand about the vertical (the ``yaw`` that ``solve`` takes)."""
        for joint, angle in zip(ARM_JOINTS, joints):
            p.resetJointState(self.body_id, joint, float(angle), physicsClientId=self.client)
        state = p.getLinkState(self.body_id, FINGERTIP_LINK, computeForwardKinematics=True,
                               physicsClientId=self.client)
        rotation = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        return float(np.arctan2(rotation[1, 0], rotation[0, 0]))

    def evaluate(self, joints: np.ndarray, position) -> IkSolution:
        """How well ``joints`` put the fingertip at ``position`` pointing straight down."""
        tip, approach = self.fingertip_pose(joints)
        pointing = float(np.arccos(np.clip(-approach[2], -1.0, 1.0)))
        return IkSolution(np.asarray(joints, dtype=float).copy(), float(np.linalg.norm(tip - position)), pointing)

    def solve(self, position, yaw: float, seeds: tuple[np.ndarray, ...] = ()) -> IkSolution:
        """Best joint vector within limits for the fingertip at ``position``, pointing down at ``yaw``.

        Starts from each seed (then the ready and rest poses), re-seeds IK from its own answer
        a few times, and returns the first reachable solution, else the best found.
        """
        target = np.asarray(position, dtype=float)
        down = p.getQuaternionFromEuler([np.pi, 0.0, float(yaw)])
        best: IkSolution | None = None
        for seed in (*seeds, *self._ready_facing(target), REST_JOINTS):
            joints = np.clip(np.asarray(seed, dtype=float), self.lower, self.upper)
            for _ in range(IK_REFINEMENTS):
                for joint, angle in zip(ARM_JOINTS, joints):
                    p.resetJointState(self.body_id, joint, float(angle), physicsClientId=self.client)
                raw = p.calculateInverseKinematics(
                    self.body_id, FINGERTIP_LINK, list(map(float, target)), down,
                    lowerLimits=list(self.lower), upperLimits=list(self.upper),
                    jointRanges=list(self.upper - self.lower), restPoses=list(READY_JOINTS),
                    maxNumIterations=100, residualThreshold=1e-5, physicsClientId=self.client)
                joints = np.clip(np.array(raw[:7]), self.lower, self.upper)
                candidate = self.evaluate(joints, target)
                if best is None or _score(candidate) < _score(best):
                    best = candidate
                if candidate.reachable:
                    return candidate
        return best


def _score(solution: IkSolution) -> float:
    return solution.position_error_m + 0.1 * solution.pointing_error_rad


def _disconnect(client: int) -> None:
    if p.isConnected(client):
        p.disconnect(client)
