"""The Franka Panda from ``pybullet_data``: joint state, IK within limits, smooth motion.

Motion really runs the physics: joint targets are interpolated along a smooth
(cosine) profile and tracked by the joint motors while the simulation steps.
Every timeout counts simulation steps, never wall time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p
import pybullet_data

ARM_JOINTS = tuple(range(7))
FINGER_JOINTS = (9, 10)
FINGERTIP_LINK = 11          # panda_grasptarget: between the fingertips
HAND_LINK = 8
REST_JOINTS = np.array([0.0, -1.5, 0.0, -2.8, 0.0, 1.5, 0.785])  # folded back, out of the camera view
JOINT_FORCE = 87.0
SIM_STEP_SECONDS = 1.0 / 240.0


@dataclass
class MotionResult:
    """How a motion ended: reached or not, the remaining fingertip error, simulated time used."""

    reached: bool
    error_m: float
    steps: int
    reason: str = ""

    @property
    def sim_seconds(self) -> float:
        return self.steps * SIM_STEP_SECONDS


class Arm:
    """The Panda mounted on the counter at the kitchen's robot base."""

    def __init__(self, world):
        self.world = world
        self.client = world.client
        base = world.kitchen.robot_base
        orientation = p.getQuaternionFromEuler([0, 0, world.kitchen.robot_yaw])
        self.body_id = p.loadURDF(str(pybullet_data.getDataPath() + "/franka_panda/panda.urdf"), base,
                                  orientation, useFixedBase=True, flags=p.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT,
                                  physicsClientId=self.client)
        self.base_position = np.asarray(base, dtype=float)
        self.base_orientation = orientation
        info = [p.getJointInfo(self.body_id, j, physicsClientId=self.client) for j in ARM_JOINTS]
        self.lower = np.array([i[8] for i in info])
        self.upper = np.array([i[9] for i in info])
        self.set_joints(REST_JOINTS)
        world.attach_robot(self)

    # -- state ---------------------------------------------------------------
    def joint_positions(self) -> np.ndarray:
        states = p.getJointStates(self.body_id, ARM_JOINTS, physicsClientId=self.client)
        return np.array([s[0] for s in states])

    def finger_opening(self) -> float:
        states = p.getJointStates(self.body_id, FINGER_JOINTS, physicsClientId=self.client)
        return float(sum(s[0] for s in states))

    def fingertip_position(self) -> np.ndarray:
        state = p.getLinkState(self.body_id, FINGERTIP_LINK, computeForwardKinematics=True,
                               physicsClientId=self.client)
        return np.array(state[4])

    def set_joints(self, joints: np.ndarray, opening: float = 0.08) -> None:
        """Teleport the arm (used only for setup, never to fake a motion)."""
        for j, q in zip(ARM_JOINTS, joints):
            p.resetJointState(self.body_id, j, float(q), physicsClientId=self.client)
        for j in FINGER_JOINTS:
            p.resetJointState(self.body_id, j, opening / 2, physicsClientId=self.client)
        self._hold(joints, opening)

    def _hold(self, joints: np.ndarray, opening: float) -> None:
        p.setJointMotorControlArray(self.body_id, ARM_JOINTS, p.POSITION_CONTROL, targetPositions=list(joints),
                                    forces=[JOINT_FORCE] * 7, physicsClientId=self.client)
        p.setJointMotorControlArray(self.body_id, FINGER_JOINTS, p.POSITION_CONTROL,
                                    targetPositions=[opening / 2] * 2, forces=[40.0] * 2,
                                    physicsClientId=self.client)

    # -- proprioception ------------------------------------------------------
    def proprioception(self) -> dict[str, float]:
        """The robot's features (thesis Table 5.1): base location and yaw (in the kitchen and relative to
        the counter), joint angles, the hand's pose relative to the body and to the counter, hand state.

        The keys, in order, are the ``source = "robot"`` features of ``bullet_world/data/features.toml``.
        """
        counter_x, counter_y = self.world.kitchen.counter_centre
        yaw = float(self.world.kitchen.robot_yaw)
        values = {"arm.base.x": float(self.base_position[0]), "arm.base.y": float(self.base_position[1]),
                  "arm.base.z": float(self.base_position[2]), "arm.base.yaw": yaw,
                  "arm.base.counter_x": float(self.base_position[0] - counter_x),
                  "arm.base.counter_y": float(self.base_position[1] - counter_y), "arm.base.counter_yaw": yaw}
        values.update({f"arm.joint{j + 1}": float(q) for j, q in enumerate(self.joint_positions())})
        position, orientation = self._hand_pose()
        inverse = p.invertTransform(self.base_position.tolist(), self.base_orientation)
        body_position, body_orientation = p.multiplyTransforms(*inverse, position, orientation)
        values.update(self._pose_features("hand", body_position, body_orientation))
        counter_position = (position[0] - counter_x, position[1] - counter_y, position[2])  # counter top is z = 0
        values.update(self._pose_features("hand.counter", counter_position, orientation))
        opening = self.finger_opening()
        values.update({"hand.opening": opening, "hand.closed": float(opening < self.HAND_CLOSED_BELOW_M)})
        return values

    HAND_CLOSED_BELOW_M = 0.04  # the hand counts as closed when its fingers are less than half open

    @staticmethod
    def _pose_features(prefix: str, position, orientation) -> dict[str, float]:
        """``prefix.x/y/z`` and ``prefix.qx/qy/qz/qw`` of one pose (quaternion with qw >= 0, so it is unique)."""
        quaternion = np.asarray(orientation, dtype=float) * (1.0 if orientation[3] >= 0 else -1.0)
        names = ("x", "y", "z", "qx", "qy", "qz", "qw")
        return {f"{prefix}.{name}": float(value) for name, value in zip(names, (*position, *quaternion))}

    def _hand_pose(self) -> tuple[tuple, tuple]:
        """World position and orientation (quaternion) of the point between the fingertips."""
        state = p.getLinkState(self.body_id, FINGERTIP_LINK, computeForwardKinematics=True,
                               physicsClientId=self.client)
        return tuple(state[4]), tuple(state[5])

    # -- kinematics and motion ------------------------------------------------
    def inverse_kinematics(self, position, yaw: float = 0.0) -> np.ndarray:
        """Joint angles (within limits) that put the fingertip at ``position``, pointing down."""
        down = p.getQuaternionFromEuler([np.pi, 0.0, yaw])
        solution = p.calculateInverseKinematics(
            self.body_id, FINGERTIP_LINK, list(map(float, position)), down,
            lowerLimits=list(self.lower), upperLimits=list(self.upper),
            jointRanges=list(self.upper - self.lower), restPoses=list(REST_JOINTS),
            maxNumIterations=200, residualThreshold=1e-4, physicsClientId=self.client,
        )
        return np.clip(np.array(solution[:7]), self.lower, self.upper)

    def move_to_joints(self, target: np.ndarray, opening: float | None = None, steps: int = 240,
                       settle_steps: int = 240, tolerance: float = 0.01) -> MotionResult:
        """Track a cosine-interpolated joint path with the motors, then settle."""
        start = self.joint_positions()
        opening = self.finger_opening() if opening is None else opening
        for k in range(1, steps + 1):
            blend = 0.5 - 0.5 * np.cos(np.pi * k / steps)
            self._hold(start + blend * (target - start), opening)
            p.stepSimulation(physicsClientId=self.client)
        used = steps
        for _ in range(settle_steps):
            if np.max(np.abs(self.joint_positions() - target)) < tolerance:
                break
            p.stepSimulation(physicsClientId=self.client)
            used += 1
        error = float(np.max(np.abs(self.joint_positions() - target)))
        return MotionResult(error < tolerance * 3, error, used, "" if error < tolerance * 3 else "joint tracking")

    def move_fingertip_to(self, position, yaw: float = 0.0, steps: int = 240, tolerance_m: float = 0.01,
                          opening: float | None = None) -> MotionResult:
        """Move so that the fingertip reaches ``position`` pointing down; report the remaining error."""
        joints = self.inverse_kinematics(position, yaw)
        motion = self.move_to_joints(joints, opening=opening, steps=steps)
        error = float(np.linalg.norm(self.fingertip_position() - np.asarray(position)))
        reached = error <= tolerance_m
        return MotionResult(reached, error, motion.steps, "" if reached else "target out of reach")

    def rest(self, rng: np.random.Generator | None = None) -> MotionResult:
        """Return to the rest pose (slightly varied when a generator is given), out of the camera's way."""
        target = REST_JOINTS.copy()
        if rng is not None:
            target += rng.normal(0.0, 0.03, 7)
        return self.move_to_joints(np.clip(target, self.lower, self.upper), opening=0.08)
