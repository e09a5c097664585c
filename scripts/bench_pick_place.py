"""Pick-place benchmark: seeded attempts across object kinds and kitchens, judged by the simulator's truth.

Every attempt puts one recipe object (a kind from the serve-pasta and
serve-salad catalogues, drawn afresh) at a free spot inside a random semantic
location of the kitchen, with two other objects as clutter, looks at it with
the camera, and asks ``Manipulator.pick_place`` to put it inside another
random location. An attempt succeeds when the robot reports success *and*
the simulator agrees: the object's true centre lies inside the destination
region and it stands upright. Kitchens take turns.

``--random`` runs the robustness mode instead: perception errors, place
points anywhere on (or off) the counter, unreachable spots, objects too wide
for the gripper. Nothing may escape as an exception; every attempt must end
with a result and a reason. The last line of ``--json`` output is one JSON
object: attempts, success_rate, failures_by_reason, sim_seconds_per_attempt
(plus exceptions, wall_seconds, grasp mode and kitchens).

    python scripts/bench_pick_place.py --attempts 200 --json
    python scripts/bench_pick_place.py --random --attempts 1000 --json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
from collections import Counter

import numpy as np
import pybullet as p

from bullet_world.catalogue import load_kitchen, load_object_kinds
from bullet_world.perception import measure_objects
from bullet_world.recipes.layout import Placer, object_radius_and_height
from bullet_world.recipes.setup import load_recipe_setup
from bullet_world.world import World
from robot import Arm
from robot.grasping import GRASP_MODES, GraspTarget, Obstacle
from robot.pick_place import Manipulator

CATALOGUES = ("serve-pasta", "serve-salad")
KITCHENS = ("kitchen-1", "kitchen-2", "kitchen-3")
CLUTTER = 2
SETUP_TRIES = 10
PLACE_MARGIN_M = 0.02   # destination spots keep this far inside the region (placement accuracy is about 1 cm)
HAND_RADIUS_M = 0.045   # the open fingers sweep this radius around the object when releasing
UPRIGHT_TILT_RAD = 0.35


class Bench:
    """One kitchen with the arm; attempts add and remove their own objects."""

    def __init__(self, kitchen: str, mode: str, seed: int):
        self.world = World(task="serve-pasta", kitchen=kitchen, seed=seed)
        self.arm = Arm(self.world)
        self.manipulator = Manipulator(self.arm, mode)
        locations = tuple(self.world.kitchen.locations)
        self.placer = Placer(self.world.kitchen, load_recipe_setup("serve-pasta"), locations)
        self.kinds = [kind for name in CATALOGUES for kind in load_object_kinds(name)]
        self.placement_errors: list[float] = []

    def close(self) -> None:
        self.manipulator.close()
        self.world.close()

    def _spawn(self, rng: np.random.Generator, at: str, others: list) -> tuple[int, float] | None:
        kind = self.kinds[rng.integers(len(self.kinds))]
        draw = kind.sample(rng)
        radius, _ = object_radius_and_height(kind, draw)
        spot = self.placer.sample(at, radius, others, rng)
        if spot is None:
            return None
        others.append((spot, radius))
        return self.world.add_object(kind, spot, float(rng.uniform(0, np.pi)), draw=draw), radius

    def _perceive(self, body: int) -> tuple[GraspTarget, list[Obstacle]] | None:
        """The camera's view: the object to move, and every other object as an obstacle."""
        images = self.world.render()
        bodies = list(self.world.object_bodies)
        measured = measure_objects(images.rgb, images.depth_buffer, images.segmentation, images.view_matrix,
                                   images.projection_matrix, bodies)
        if measured[body] is None:
            return None
        obstacles = [Obstacle.from_measurement(m) for b, m in measured.items() if b != body and m is not None]
        return GraspTarget.from_measurement(measured[body]), obstacles

    def attempt(self, rng: np.random.Generator, random_mode: bool) -> tuple[bool, str, float, str]:
        """One attempt; returns (success judged by the truth, reason, simulated seconds, description)."""
        try:
            for _ in range(SETUP_TRIES):  # a scene where the object and a free destination spot both exist
                setup = self._setup(rng, random_mode)
                if setup is not None:
                    break
                self._clear()
            else:
                return False, "no-free-spot", 0.0, "no scene could be set up"
            body, target, obstacles, place, region, what = setup
            result = self.manipulator.pick_place(target, place, region, obstacles)
            truth = self._truth_agrees(body, region) if result.success else False
            if result.success:
                true_xy = p.getBasePositionAndOrientation(body, physicsClientId=self.world.client)[0][:2]
                self.placement_errors.append(float(np.linalg.norm(np.asarray(true_xy) - place)))
            reason = result.reason if not result.success else ("" if truth else "robot-and-truth-disagree")
            return result.success and truth, reason, result.sim_seconds, f"{what}: {result.detail}"
        finally:
            self._clear()

    def _setup(self, rng: np.random.Generator, random_mode: bool):
        """Spawn the object and clutter, look, and pick a destination; None when something does not fit."""
        names = list(self.world.kitchen.locations)
        start, end = rng.choice(len(names), size=2, replace=False)
        others: list = []
        spawned = self._spawn(rng, names[start], others)
        if spawned is None:
            return None
        body, _ = spawned
        what = f"{self.world.kitchen.name}: {self.world.objects[-1].kind.name} from {names[start]} to {names[end]}"
        for _ in range(CLUTTER):
            self._spawn(rng, names[int(rng.integers(len(names)))], others)
        for _ in range(30):
            p.stepSimulation(physicsClientId=self.world.client)
        seen = self._perceive(body)
        if seen is None:
            return None
        target, obstacles = seen
        if random_mode:
            target, place = self._distort(target, rng)
        else:
            place = self._free_place(names[end], target, others, rng)
            if place is None:
                return None
        return body, target, obstacles, place, self.world.kitchen.locations[names[end]], what

    def _clear(self) -> None:
        for body in list(self.world.object_bodies):
            self.world.remove_object(body)

    def _free_place(self, at: str, target: GraspTarget, others: list, rng: np.random.Generator):
        """A destination spot clear of the clutter (counting the open fingers), well inside the region."""
        radius = max(0.5 * float(np.hypot(target.length, target.width)), HAND_RADIUS_M)
        standing = [(xy, r) for xy, r in others if np.linalg.norm(np.asarray(target.centre[:2]) - xy) > 0.03]
        low, high = self.placer.bounds(at, 0.0)
        for _ in range(200):
            spot = rng.uniform(low + PLACE_MARGIN_M, high - PLACE_MARGIN_M)
            if self.placer.feasible(at, spot, radius, standing):
                return spot
        return None

    @staticmethod
    def _distort(target: GraspTarget, rng: np.random.Generator) -> tuple[GraspTarget, np.ndarray]:
        """Robustness mode: wrong perception, and place points anywhere within 1.2 m."""
        centre = np.asarray(target.centre) + rng.normal(0, [0.02, 0.02, 0.01])
        scale = rng.uniform(0.5, 2.0, 3) if rng.random() < 0.3 else np.ones(3)
        distorted = GraspTarget(tuple(centre), target.length * scale[0], target.width * scale[1],
                                target.height * scale[2], float(rng.uniform(-4, 4)))
        return distorted, rng.uniform(-1.2, 1.2, 2)

    def _truth_agrees(self, body: int, region) -> bool:
        position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=self.world.client)
        up = np.array(p.getMatrixFromQuaternion(orientation)).reshape(3, 3)[:, 2]
        return bool(region.contains(position[:2]) and np.arccos(np.clip(up[2], -1, 1)) < UPRIGHT_TILT_RAD)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--attempts", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--grasp", choices=GRASP_MODES, default=GRASP_MODES[0])
    parser.add_argument("--kitchens", nargs="+", default=list(KITCHENS))
    parser.add_argument("--random", action="store_true", help="robustness mode (see the module doc)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    parser.add_argument("--verbose", action="store_true", help="describe every failed attempt on stderr")
    args = parser.parse_args(argv)
    if args.attempts < 1:
        parser.error("--attempts must be at least 1")
    kitchens = []
    for name in args.kitchens:
        try:
            load_kitchen(name)
            kitchens.append(name)
        except ValueError as error:
            print(f"skipping {name}: {error}", file=sys.stderr)
    if not kitchens:
        parser.error("none of the --kitchens exists")
    benches = {name: Bench(name, args.grasp, args.seed) for name in kitchens}
    rng = np.random.default_rng(args.seed)
    reasons: Counter = Counter()
    successes, exceptions, sim_seconds = 0, 0, 0.0
    started = time.perf_counter()
    try:
        for number in range(args.attempts):
            bench = benches[kitchens[number % len(kitchens)]]
            try:
                success, reason, seconds, what = bench.attempt(rng, args.random)
            except Exception:  # counted and shown: the benchmark's job is to find these
                exceptions += 1
                traceback.print_exc()
                success, reason, seconds, what = False, "exception", 0.0, "exception"
            if args.verbose and not success:
                print(f"attempt {number}: {reason} - {what}", file=sys.stderr)
            successes += success
            sim_seconds += seconds
            if not success:
                reasons[reason] += 1
            if (number + 1) % 50 == 0:
                print(f"{number + 1} attempts: {successes} succeeded", file=sys.stderr, flush=True)
    finally:
        for bench in benches.values():
            bench.close()
    wall = time.perf_counter() - started
    errors = [error for bench in benches.values() for error in bench.placement_errors]
    summary = {"attempts": args.attempts, "success_rate": round(successes / args.attempts, 4),
               "failures_by_reason": dict(sorted(reasons.items())),
               "sim_seconds_per_attempt": round(sim_seconds / args.attempts, 2), "exceptions": exceptions,
               "placement_error_m": {"median": round(float(np.median(errors)), 4) if errors else None,
                                     "p95": round(float(np.percentile(errors, 95)), 4) if errors else None},
               "wall_seconds": round(wall, 1), "grasp": args.grasp, "mode": "random" if args.random else "seeded",
               "kitchens": kitchens}
    print(f"{successes}/{args.attempts} succeeded ({summary['success_rate']:.1%}); failures {dict(reasons)}; "
          f"{summary['sim_seconds_per_attempt']} s simulated per attempt; {exceptions} exceptions; {wall:.0f} s wall")
    if args.json:
        print(json.dumps(summary))
    return 0 if exceptions == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
