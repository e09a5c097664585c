"""Pick an object up and put it down inside a region: a real, checked motion sequence.

``Manipulator.pick_place(target, place_xy, region)`` runs, all in physics steps:

1. plan: every waypoint is solved on the ``KinematicTwin`` first (IK within
   joint limits, fingertip pointing down); an unreachable waypoint fails the
   attempt before the arm moves ("ik-unreachable");
2. approach to a point above the object, fingers open, the hand turned so
   that its palm and fingers keep clear of the other perceived objects;
3. descend in a straight line to the grasp height (``GraspTarget.grasp_tip_height``);
4. close the fingers; nothing between both fingers is "grasp-missed";
5. lift straight up to the travel height, carry along a straight line at that
   height, lower to the place height; losing the object while lifting or
   carrying is "dropped";
6. release, retreat straight up, and fold back to the rest pose;
7. look: render the camera and measure the released object. Its perceived
   centre must lie inside ``region`` ("placed-outside-region") and its perceived
   height must match the grasped one ("tipped-over"); an object the camera
   cannot see is "not-visible".

Every failure is returned as a ``PickPlaceResult`` with a reason, never raised.
Every wait and timeout counts simulation steps; ``step_budget`` bounds the whole
attempt ("step-budget-exceeded").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from bullet_world.perception import measure_objects
from robot.arm import SIM_STEP_SECONDS, Arm
from robot.grasping import FRICTION, MAX_OPENING_M, GraspTarget, Gripper, Obstacle, hand_clearance
from robot.kinematics import KinematicTwin

TRAVEL_TIP_HEIGHTS_M = (0.28, 0.24, 0.20)  # fingertip heights tried for carrying, highest first
APPROACH_CLEARANCE_M = 0.06     # the approach point is at least this far above the object's top
PLACE_DROP_M = 0.004           # the object's bottom is released this far above the surface
WAYPOINT_SPACING_M = 0.06       # straight-line motions are split into waypoints this far apart
WAYPOINT_TURN_RAD = 0.5         # ... and so that the hand turns at most this much between waypoints
MAX_YAWS_TRIED = 6              # hand yaws tried per phase, clearest first
STEPS_PER_METRE = 1400          # motion speed along straight lines (about 0.17 m/s)
MIN_SEGMENT_STEPS = 20
APPROACH_STEPS = 300
REST_STEPS = 240
STEP_BUDGET = 4000              # about 17 s of simulated time per attempt
TIPPED_HEIGHT_CHANGE = 0.25     # relative change of perceived height that counts as tipped over
FAILURE_REASONS = (
    "invalid-target", "too-wide-for-gripper", "ik-unreachable", "grasp-missed", "dropped",
    "placed-outside-region", "tipped-over", "not-visible", "step-budget-exceeded",
)


class Region(Protocol):
    """Anything that says whether a point (x, y) in the world frame is inside it."""

    def contains(self, xy) -> bool: ...


@dataclass
class PickPlaceResult:
    """How one pick-place attempt ended; ``reason`` is "" on success, else one of FAILURE_REASONS."""

    success: bool
    reason: str
    detail: str
    steps: int
    phase: str
    held_body: int | None = None
    placed_position: np.ndarray | None = field(default=None, repr=False)

    @property
    def sim_seconds(self) -> float:
        return self.steps * SIM_STEP_SECONDS


@dataclass
class _Segment:
    joints: list[np.ndarray]
    steps: list[int]


class Manipulator:
    """The arm with a gripper and a kinematic twin: grasp, carry and place (see the module doc)."""

    def __init__(self, arm: Arm, mode: str = FRICTION):
        self.arm = arm
        self.gripper = Gripper(arm, mode, ignore_bodies=(arm.world.counter_body,))
        self.twin = KinematicTwin(arm)

    def close(self) -> None:
        self.twin.close()

    # ------------------------------------------------------------------ public
    def pick_place(self, target: GraspTarget, place_xy, region: Region | None = None,
                   obstacles: Sequence[Obstacle] = (), step_budget: int = STEP_BUDGET) -> PickPlaceResult:
        """Move the object described by ``target`` so that it stands at ``place_xy`` (inside ``region``).

        ``obstacles`` are the other perceived objects: the hand turns so that its palm and open fingers
        keep clear of them when it reaches down to grasp and to put down (``grasping.hand_clearance``).
        """
        steps = 0

        def failed(reason: str, detail: str, phase: str, body: int | None = None) -> PickPlaceResult:
            return PickPlaceResult(False, reason, detail, steps, phase, body)

        problem = target.problem()
        place = np.asarray(place_xy, dtype=float).reshape(-1)
        if problem:
            return failed(problem, f"cannot grasp {target}", "plan")
        if place.size != 2 or not np.all(np.isfinite(place)):
            return failed("invalid-target", f"place point must be two finite numbers, got {place_xy!r}", "plan")
        plan = self._plan(target, place, tuple(obstacles))
        if isinstance(plan, str):
            return failed("ik-unreachable", plan, "plan")
        approach, descend, lift_carry_lower, retreat = plan

        steps += self._run(approach, MAX_OPENING_M)
        steps += self._run(descend, MAX_OPENING_M)
        body = self.gripper.close()
        steps += self.gripper.last_steps
        if body is None:
            self.gripper.open()
            steps += self.gripper.last_steps
            steps += self._retreat_to_rest(retreat_from_here=True)
            return failed("grasp-missed", "no object between both fingers after closing", "grasp")
        for phase, segment in zip(("lift", "carry", "lower"), lift_carry_lower):
            steps += self._run(segment, self.gripper.command)
            # While lowering, the object may touch down and slip a little: the look at the end judges it.
            dropped = phase != "lower" and not self.gripper.still_holding()
            if dropped or steps > step_budget:
                self.gripper.open()
                steps += self.gripper.last_steps + self._retreat_to_rest(retreat_from_here=True)
                if dropped:
                    return failed("dropped", f"the fingers lost the object during the {phase}", phase, body)
                return failed("step-budget-exceeded", f"{steps} steps > budget {step_budget}", phase, body)
        self.gripper.open()
        steps += self.gripper.last_steps
        steps += self._run(retreat, MAX_OPENING_M)
        steps += self.arm.rest().steps
        if steps > step_budget:
            return failed("step-budget-exceeded", f"{steps} steps > budget {step_budget}", "retreat", body)
        return self._look(target, body, region, steps)

    # ---------------------------------------------------------------- planning
    def _plan(self, target: GraspTarget, place: np.ndarray, obstacles: tuple[Obstacle, ...]):
        """Joint waypoints for every phase, solved on the twin; a string says what is unreachable.

        Hand yaws are tried clearest first (pick and place separately; the hand turns while carrying),
        then lower travel heights.
        """
        x, y, _ = target.centre
        grasp_z = target.grasp_tip_height()
        place_z = grasp_z + PLACE_DROP_M  # put down on the surface it was picked from
        lowest = target.top + APPROACH_CLEARANCE_M
        heights = [z for z in TRAVEL_TIP_HEIGHTS_M if z >= lowest] or [lowest]
        pick_yaws = _clearest(target.candidate_hand_yaws(), (x, y), grasp_z, obstacles)
        round_place = GraspTarget((*place, target.centre[2]), 1.0, 1.0, target.height, target.yaw)
        place_yaws = _clearest(round_place.candidate_hand_yaws(), place, place_z, obstacles)
        for name, point, yaws in (("the object", (x, y), pick_yaws), ("the place", place, place_yaws)):
            if not any(self.twin.solve([*point, heights[-1]], yaw).reachable for yaw in yaws[:2]):
                return f"no reachable plan: the point above {name} is out of reach"
        reasons = []
        for travel_z in heights:
            for pick_yaw in pick_yaws:
                for place_yaw in _nearest_first(place_yaws, pick_yaw):
                    plan = self._plan_with(x, y, grasp_z, place, place_z, travel_z, pick_yaw, place_yaw)
                    if not isinstance(plan, str):
                        return plan
                    reasons.append(f"{plan} (height {travel_z:.2f}, yaws {pick_yaw:.2f}/{place_yaw:.2f})")
        return "no reachable plan: " + "; ".join(reasons[:2])

    def _plan_with(self, x, y, grasp_z, place, place_z, travel_z, pick_yaw, place_yaw):
        above_pick = np.array([x, y, travel_z])
        above_place = np.array([place[0], place[1], travel_z])
        first = self.twin.solve(above_pick, pick_yaw, (self.arm.joint_positions(),))
        if not first.reachable:
            return "the point above the object is out of reach"
        try:
            descend, joints = self._line(first.joints, above_pick, np.array([x, y, grasp_z]), pick_yaw)
            lift, joints = self._line(joints, np.array([x, y, grasp_z]), above_pick, pick_yaw)
            carry, joints = self._line(joints, above_pick, above_place, pick_yaw, place_yaw)
            lower, joints = self._line(joints, above_place, np.array([*place, place_z]), place_yaw)
            retreat, _ = self._line(joints, np.array([*place, place_z]), above_place, place_yaw)
        except _Unreachable as error:
            return str(error)
        return _Segment([first.joints], [APPROACH_STEPS]), descend, (lift, carry, lower), retreat

    def _line(self, seed: np.ndarray, start: np.ndarray, end: np.ndarray, yaw: float, end_yaw: float | None = None):
        """Waypoints along a straight fingertip line (the hand turning from ``yaw`` to ``end_yaw``),
        each IK-solved from the previous one."""
        turn = 0.0 if end_yaw is None else float(np.mod(end_yaw - yaw + np.pi, 2 * np.pi) - np.pi)
        length = float(np.linalg.norm(end - start))
        count = max(1, int(np.ceil(max(length / WAYPOINT_SPACING_M, abs(turn) / WAYPOINT_TURN_RAD))))
        joints, steps = [], []
        current = seed
        for k in range(1, count + 1):
            point = start + (end - start) * k / count
            solution = self.twin.solve(point, yaw + turn * k / count, (current,))
            if not solution.reachable:
                raise _Unreachable(f"point {np.round(point, 3).tolist()} is out of reach")
            current = solution.joints
            joints.append(current)
            steps.append(max(MIN_SEGMENT_STEPS, int(STEPS_PER_METRE * length / count)))
        return _Segment(joints, steps), current

    # --------------------------------------------------------------- execution
    def _run(self, segment: _Segment, opening: float) -> int:
        """Track the waypoints; only the last one waits for the joints to settle."""
        used = 0
        last = len(segment.joints) - 1
        for index, (joints, steps) in enumerate(zip(segment.joints, segment.steps)):
            settle = 240 if index == last else 0
            used += self.arm.move_to_joints(joints, opening=opening, steps=steps, settle_steps=settle,
                                            tolerance=0.003).steps
        return used

    def _retreat_to_rest(self, retreat_from_here: bool) -> int:
        """After a failure: straight up from wherever the hand is, then fold back to rest."""
        used = 0
        if retreat_from_here:
            tip = self.arm.fingertip_position()
            above = np.array([tip[0], tip[1], max(tip[2], TRAVEL_TIP_HEIGHTS_M[-1])])
            yaw = self.twin.hand_yaw(self.arm.joint_positions())
            solution = self.twin.solve(above, yaw, (self.arm.joint_positions(),))
            if solution.reachable:
                used += self.arm.move_to_joints(solution.joints, opening=MAX_OPENING_M, steps=150).steps
        return used + self.arm.rest().steps

    def _look(self, target: GraspTarget, body: int, region: Region | None, steps: int) -> PickPlaceResult:
        """Render the camera and judge the placement from the released object's measurement."""
        world = self.arm.world
        images = world.render()
        seen = bool(np.any(images.segmentation == body))  # (perception assumes some pixels to measure)
        measured = measure_objects(images.rgb, images.depth_buffer, images.segmentation, images.view_matrix,
                                   images.projection_matrix, [body])[body] if seen else None
        if measured is None:
            return PickPlaceResult(False, "not-visible", "the camera cannot see the placed object", steps, "look",
                                   body)
        centre = np.asarray(measured.centroid, dtype=float)
        if abs(measured.height - target.height) > max(0.015, TIPPED_HEIGHT_CHANGE * target.height):
            return PickPlaceResult(False, "tipped-over", f"perceived height {measured.height:.3f} m, grasped "
                                   f"{target.height:.3f} m", steps, "look", body, centre)
        if region is not None and not region.contains(centre[:2]):
            return PickPlaceResult(False, "placed-outside-region", f"object seen at {np.round(centre, 3).tolist()}",
                                   steps, "look", body, centre)
        return PickPlaceResult(True, "", "placed", steps, "look", body, centre)


def _clearest(yaws: list[float], xy, tip_z: float, obstacles: tuple[Obstacle, ...]) -> list[float]:
    """The yaws with the hand clear of the obstacles, clearest first; all of them if none is clear."""
    gaps = [hand_clearance(xy, yaw, tip_z, obstacles) for yaw in yaws]
    order = sorted(range(len(yaws)), key=lambda i: -min(gaps[i], 1.0))
    clear = [yaws[i] for i in order if gaps[i] > 0]
    return (clear or [yaws[i] for i in order])[:MAX_YAWS_TRIED]


def _nearest_first(yaws: list[float], reference: float) -> list[float]:
    """Clear place yaws, the one needing the least wrist turn from ``reference`` first."""
    clear = yaws[: max(2, len(yaws) // 2)]
    return sorted(clear, key=lambda yaw: abs(np.mod(yaw - reference + np.pi, 2 * np.pi) - np.pi))


class _Unreachable(Exception):
    """Internal: a waypoint of the plan is out of reach (turned into a result, never escapes)."""

