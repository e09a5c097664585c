"""Benchmark: build, render and measure a 55-object scene (goal: <= 150 ms per scene).

Phases, timed separately on every scene (wall clock and process CPU time):

* build:    clear the old objects, draw 55 new ones, place them without
            overlap, create their bodies (meshes, textures, collision shapes)
* render:   the TinyRenderer frame with the counter painted analytically, plus sensor noise
* measure:  one-pass perception of every object (OpenCV + numpy)
* features: the feature matrix (interest points, neighbours, room and robot sensors)

References measured in the same run, on the same scenes:

* render with the counter rendered by the TinyRenderer (no analytic backdrop)
* measure with one segmentation mask per object (the foundation's approach)

    .venv/bin/python scripts/bench_scene.py --scenes 20 --json
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bullet_world.perception import deproject, measure_object, measure_objects  # noqa: E402
from bullet_world.world import World  # noqa: E402

GOAL_MS = 150.0


def measure_per_mask(images, bodies) -> dict:
    """The reference: one boolean mask and one deprojection per object."""
    results = {}
    for body in bodies:
        rows, cols = np.nonzero(images.segmentation == body)
        points = deproject(images.depth_buffer, images.view_matrix, images.projection_matrix, rows, cols)
        results[body] = measure_object(points, images.rgb[rows, cols], body, 0.0)
    return results


class Clock:
    """Wall and CPU milliseconds of each timed call, per phase."""

    def __init__(self):
        self.wall: dict[str, list[float]] = {}
        self.cpu: dict[str, list[float]] = {}

    def time(self, phase: str, function, *args, **kwargs):
        wall, cpu = time.perf_counter(), time.process_time()
        result = function(*args, **kwargs)
        self.wall.setdefault(phase, []).append(1000 * (time.perf_counter() - wall))
        self.cpu.setdefault(phase, []).append(1000 * (time.process_time() - cpu))
        return result

    def median(self, phase: str, cpu: bool = False) -> float:
        return round(float(np.median((self.cpu if cpu else self.wall)[phase])), 1)


def resident_kb() -> float:
    """Resident memory of this process (Linux), in kilobytes; 0 where /proc is missing."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
    except (OSError, ValueError, IndexError):
        return 0.0
    return pages * 4.0


def _world(objects: int, kitchen: str, seed: int, robot: bool) -> World:
    world = World(task="pack-lunchbox", kitchen=kitchen, seed=seed, objects_per_scene=objects)
    if robot:
        from robot import Arm

        Arm(world)
    world.new_scene(np.random.default_rng([seed, 999]))  # warm up: files, textures, caches
    return world


def _populate(world: World, clock: Clock, seed: int, index: int) -> None:
    rng = np.random.default_rng([seed, index])
    if world.robot is not None:
        world.robot.rest(rng)  # the arm's own time, not the scene's
    clock.time("build", world.populate, rng, rest_robot=False)


def run(scenes: int, objects: int, kitchen: str, seed: int, robot: bool) -> dict:
    """The pipeline on ``scenes`` scenes, then the references on the same scenes in a second world."""
    clock = Clock()
    with _world(objects, kitchen, seed, robot) as world:
        memory_before = resident_kb()
        for index in range(scenes):
            _populate(world, clock, seed, index)
            images = clock.time("render", world.render)
            args = (images.rgb, images.depth_buffer, images.segmentation, images.view_matrix,
                    images.projection_matrix, list(world.object_bodies))
            clock.time("measure", measure_objects, *args)
            clock.time("measure+features", world.observe_images, images)
        memory_growth = (resident_kb() - memory_before) / scenes
    with _world(objects, kitchen, seed, robot) as world:
        world.camera.set_backdrop(None)
        reference = Clock()
        for index in range(scenes):
            _populate(world, reference, seed, index)
            images = clock.time("reference render (counter rendered)", world.render)
            clock.time("reference measure (mask per object)", measure_per_mask, images, list(world.object_bodies))
    phases = ("build", "render", "measure+features")
    per_scene_wall = np.sum([clock.wall[p] for p in phases], axis=0)
    per_scene_cpu = np.sum([clock.cpu[p] for p in phases], axis=0)
    total_wall, total_cpu = float(np.median(per_scene_wall)), float(np.median(per_scene_cpu))
    return {
        "scenes": scenes, "objects_per_scene": objects, "kitchen": kitchen, "robot": robot,
        "ms_per_scene": round(total_wall, 1), "cpu_ms_per_scene": round(total_cpu, 1), "goal_ms": GOAL_MS,
        "best_ms_per_scene": round(float(per_scene_wall.min()), 1),
        "memory_kb_per_scene": round(memory_growth, 1), "load_average": round(os.getloadavg()[0], 2),
        "phases_ms": {phase: clock.median(phase) for phase in clock.wall},
        "phases_cpu_ms": {phase: clock.median(phase, cpu=True) for phase in clock.cpu},
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", type=int, default=20)
    parser.add_argument("--objects", type=int, default=55)
    parser.add_argument("--kitchen", default="kitchen-1")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--robot", action="store_true",
                        help="attach the arm: its features join the matrix (its rest motion stays untimed)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    result = run(args.scenes, args.objects, args.kitchen, args.seed, args.robot)
    print(f"{args.objects}-object scenes in {args.kitchen}, median of {args.scenes}:")
    for phase, wall in result["phases_ms"].items():
        print(f"  {phase:<38} {wall:7.1f} ms wall  {result['phases_cpu_ms'][phase]:7.1f} ms CPU")
    verdict = "meets" if result["ms_per_scene"] <= GOAL_MS else "misses"
    print(f"  build + render + measure + features    {result['ms_per_scene']:7.1f} ms wall  "
          f"{result['cpu_ms_per_scene']:7.1f} ms CPU  ({verdict} the {GOAL_MS:.0f} ms goal)")
    print(f"  fastest scene: {result['best_ms_per_scene']} ms wall (the machine's load inflates the medians)")
    print(f"  memory growth per scene: {result['memory_kb_per_scene']} kB; "
          f"load average {result['load_average']} on {os.cpu_count()} CPUs")
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
