"""Perception against the simulator's ground truth, over many objects in many scenes.

Size error: for each object, the largest of its length, width and height
errors (so a median of 2 mm means half the objects have every box dimension
within 2 mm). Location error: the 3-D distance between the perceived and the
true bounding-box centre. Both in millimetres.
"""

from __future__ import annotations

import time

import numpy as np

from bullet_world.world import HiddenObjectError, World

SIZE_FEATURES = ("size.length", "size.width", "size.height")


def scene_errors(scene) -> tuple[np.ndarray, np.ndarray]:
    """Per object: largest box-dimension error and centre distance (metres)."""
    measured = np.column_stack([scene.feature(name) for name in SIZE_FEATURES])
    size = np.abs(measured - scene.truth.sizes).max(axis=1)
    location = np.linalg.norm(scene.positions - scene.truth.positions, axis=1)
    return size, location


def timed_scene(world: World, rng: np.random.Generator):
    """A new scene and the wall and CPU seconds spent building, rendering and measuring it (an attached
    robot's rest motion happens first, untimed: it is the arm's time, not the scene's)."""
    for _ in range(3):
        if world.robot is not None:
            world.robot.rest(rng)
        wall, cpu = time.perf_counter(), time.process_time()
        world.populate(rng, rest_robot=False)
        try:
            scene = world.observe()
        except HiddenObjectError:
            continue
        return scene, time.perf_counter() - wall, time.process_time() - cpu
    raise HiddenObjectError("three samples in a row hid an object from the camera")


def _summary(values_m: np.ndarray) -> dict[str, float]:
    millimetres = np.asarray(values_m) * 1000.0
    return {"median": round(float(np.median(millimetres)), 2), "p95": round(float(np.percentile(millimetres, 95)), 2)}


def perception_check(kitchens=("kitchen-1", "kitchen-2", "kitchen-3"), task: str = "pack-lunchbox",
                     min_objects: int = 500, objects_per_scene: int = 55, seed: int = 0,
                     progress=None, robot_factory=None) -> dict:
    """Build scenes in every kitchen in turn until ``min_objects`` objects were measured; report errors,
    per kind medians, the feature count and the time per scene (build + render + measure + features).
    ``robot_factory(world)`` attaches a robot (``robot.Arm``) so that its features are counted too."""
    size_errors, location_errors, kinds, seconds, cpu = [], [], [], [], []
    worlds = {name: World(task=task, kitchen=name, seed=seed, objects_per_scene=objects_per_scene)
              for name in kitchens}
    if robot_factory is not None:
        for world in worlds.values():
            robot_factory(world)
    feature_count = 0
    try:
        scene_index = 0
        while len(kinds) < min_objects:
            name = kitchens[scene_index % len(kitchens)]
            world = worlds[name]
            rng = np.random.default_rng([seed, scene_index])
            scene, wall, processor = timed_scene(world, rng)
            seconds.append(wall)
            cpu.append(processor)
            size, location = scene_errors(scene)
            size_errors.append(size)
            location_errors.append(location)
            kinds += list(scene.truth.kinds)
            feature_count = len(scene.feature_names)
            scene_index += 1
            if progress:
                progress(f"{name}: scene {scene_index}: {scene.n_objects} objects in this scene, {len(kinds)} in "
                         f"total so far (of at least {min_objects})")
    finally:
        for world in worlds.values():
            world.close()
    size_all, location_all = np.concatenate(size_errors), np.concatenate(location_errors)
    kinds_array = np.array(kinds)
    per_kind = {kind: {"objects": int(np.sum(kinds_array == kind)),
                       "size_err_mm": _summary(size_all[kinds_array == kind])["median"],
                       "loc_err_mm": _summary(location_all[kinds_array == kind])["median"]}
                for kind in sorted(set(kinds))}
    return {
        "objects": len(kinds),
        "size_err_mm": _summary(size_all),
        "loc_err_mm": _summary(location_all),
        "features": feature_count,
        "ms_per_scene": round(1000.0 * float(np.median(seconds)), 1),
        "cpu_ms_per_scene": round(1000.0 * float(np.median(cpu)), 1),
        "scenes": len(seconds),
        "objects_per_scene": objects_per_scene,
        "kitchens": list(kitchens),
        "per_kind": per_kind,
    }
