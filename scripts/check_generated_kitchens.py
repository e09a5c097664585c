"""The shipped kitchens' checks on many generated kitchens (issue 52 item 2): perception (`world check`),
pointing at every object with no contact between the arm and the room, and pick-and-place (bench_pick_place).

Kitchens of seeds ``--first`` .. ``--first + --count - 1`` are written by the generator into ``--folder`` (a
temporary one by default). Per kitchen: ``--objects`` objects measured in scenes of 55 with the arm (as `teachbot
world check`), every object of one scene pointed at while every simulation step is watched for contacts with the
room's pieces, and ``--attempts`` pick-and-place attempts judged by the simulator's truth. The shipped three are
measured by the same perception loop (``--baseline-objects``) for the band: pooled size and location error median
<= 5 mm, p95 within the shipped kitchens' p95 + 10 %. The last line of ``--json`` is one JSON object.

    nice .venv/bin/python scripts/check_generated_kitchens.py --first 5000 --count 50 --attempts 4 --json
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pybullet as p

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from bench_pick_place import Bench  # noqa: E402

from bullet_world.check import scene_errors, timed_scene  # noqa: E402
from bullet_world.datafiles import available  # noqa: E402
from bullet_world.generation import generate_kitchens  # noqa: E402
from bullet_world.world import World  # noqa: E402
from robot import Arm  # noqa: E402
from robot.gestures import point_at  # noqa: E402

SCENE_OBJECTS = 55
BAND_MEDIAN_MM = 5.0
BAND_P95_SLACK = 1.10


def perception_errors(kitchen: str, objects: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Size and location errors (mm) of at least ``objects`` objects in scenes of 55, with the arm."""
    sizes, locations = [], []
    with World(task="pack-lunchbox", kitchen=kitchen, seed=seed, objects_per_scene=SCENE_OBJECTS) as world:
        Arm(world)
        scene_index = 0
        while sum(map(len, sizes)) < objects:
            scene, _, _ = timed_scene(world, np.random.default_rng([seed, scene_index]))
            size, location = scene_errors(scene)
            sizes.append(size * 1000.0)
            locations.append(location * 1000.0)
            scene_index += 1
    return np.concatenate(sizes), np.concatenate(locations)


@contextmanager
def watched_contacts(arm, world, touched: set):
    """Every simulation step looks for contacts between the arm and a piece of the room."""
    step = p.stepSimulation

    def step_and_look(*args, **kwargs):
        step(*args, **kwargs)
        for contact in p.getContactPoints(bodyA=arm.body_id, physicsClientId=world.client):
            if contact[2] in world.furniture:
                touched.add(world.furniture[contact[2]])

    p.stepSimulation = step_and_look
    try:
        yield
    finally:
        p.stepSimulation = step


def pointing(kitchen: str, seed: int) -> dict:
    """Point at every object of one scene; the objects not reached and the room pieces the arm touched."""
    touched: set[str] = set()
    with World(kitchen=kitchen, seed=seed) as world:
        arm = Arm(world)
        with watched_contacts(arm, world, touched):
            scene = world.new_scene(np.random.default_rng(seed))
            missed = [index for index in range(scene.n_objects)
                      if not point_at(arm, scene.positions[index], float(scene.tops[index])).reached]
            arm.rest()
    return {"objects": int(scene.n_objects), "missed": len(missed), "touched": sorted(touched)}


def pick_place(kitchen: str, attempts: int, seed: int) -> dict:
    bench = Bench(kitchen, "friction", seed)
    rng = np.random.default_rng(seed)
    reasons: dict[str, int] = {}
    successes = 0
    try:
        for _ in range(attempts):
            success, reason, _, _ = bench.attempt(rng, False)
            successes += success
            if not success:
                reasons[reason] = reasons.get(reason, 0) + 1
    finally:
        bench.close()
    return {"attempts": attempts, "successes": successes, "failures": reasons}


def summary(values: list[np.ndarray]) -> dict:
    pooled = np.concatenate(values)
    return {"median": round(float(np.median(pooled)), 2), "p95": round(float(np.percentile(pooled, 95)), 2)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--first", type=int, default=5000, help="seed of the first kitchen (default 5000)")
    parser.add_argument("--count", type=int, default=50, help="kitchens (default 50)")
    parser.add_argument("--objects", type=int, default=110, help="objects measured per kitchen (default 110)")
    parser.add_argument("--baseline-objects", type=int, default=550,
                        help="objects measured in the shipped kitchens, in turn (default 550)")
    parser.add_argument("--attempts", type=int, default=4, help="pick-and-place attempts per kitchen (default 4)")
    parser.add_argument("--folder", type=Path, default=None, help="where the kitchens are written (default: temp)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    baseline_size, baseline_location = [], []
    shipped = available("kitchens")
    for index, name in enumerate(shipped):   # the shipped bands, measured the same way now
        share = -(-args.baseline_objects // len(shipped))
        size, location = perception_errors(name, share, index)
        baseline_size.append(size)
        baseline_location.append(location)
    baseline = {"size_err_mm": summary(baseline_size), "loc_err_mm": summary(baseline_location)}
    print(f"shipped kitchens: {baseline}", file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory() as temporary:
        folder = args.folder or Path(temporary)
        paths = generate_kitchens(args.first, args.count, folder)
        rows, sizes, locations = [], [], []
        for path in paths:
            seed = int(path.stem.rsplit("-", 1)[1])
            size, location = perception_errors(str(path), args.objects, seed)
            sizes.append(size)
            locations.append(location)
            row = {"kitchen": path.stem, "size_err_mm": summary([size]), "loc_err_mm": summary([location]),
                   "pointing": pointing(str(path), seed), "pick_place": pick_place(str(path), args.attempts, seed)}
            rows.append(row)
            print(json.dumps(row), file=sys.stderr, flush=True)
    size_all, location_all = summary(sizes), summary(locations)
    bands = {"size_p95_mm": round(baseline["size_err_mm"]["p95"] * BAND_P95_SLACK, 2),
             "loc_p95_mm": round(baseline["loc_err_mm"]["p95"] * BAND_P95_SLACK, 2), "median_mm": BAND_MEDIAN_MM}
    attempts = sum(row["pick_place"]["attempts"] for row in rows)
    successes = sum(row["pick_place"]["successes"] for row in rows)
    failures: dict[str, int] = {}
    for row in rows:
        for reason, count in row["pick_place"]["failures"].items():
            failures[reason] = failures.get(reason, 0) + count
    pointed = sum(row["pointing"]["objects"] for row in rows)
    missed = sum(row["pointing"]["missed"] for row in rows)
    touched = sorted({f"{row['kitchen']}: {piece}" for row in rows for piece in row["pointing"]["touched"]})
    result = {
        "kitchens": len(rows), "seeds": [args.first, args.first + args.count - 1], "objects_per_kitchen": args.objects,
        "baseline": baseline, "bands": bands, "size_err_mm": size_all, "loc_err_mm": location_all,
        "kitchens_within_bands": sum(row["size_err_mm"]["median"] <= BAND_MEDIAN_MM
                                     and row["loc_err_mm"]["median"] <= BAND_MEDIAN_MM
                                     and row["size_err_mm"]["p95"] <= bands["size_p95_mm"]
                                     and row["loc_err_mm"]["p95"] <= bands["loc_p95_mm"] for row in rows),
        "perception_within_bands": bool(size_all["median"] <= BAND_MEDIAN_MM
                                        and location_all["median"] <= BAND_MEDIAN_MM
                                        and size_all["p95"] <= bands["size_p95_mm"]
                                        and location_all["p95"] <= bands["loc_p95_mm"]),
        "pointing": {"objects": pointed, "missed": missed, "touched": touched},
        "pick_place": {"attempts": attempts, "successes": successes,
                       "success_rate": round(successes / attempts, 4) if attempts else None, "failures": failures},
        "wall_seconds": round(time.perf_counter() - started, 1),
        "per_kitchen": rows,
    }
    print(f"{len(rows)} kitchens (seeds {args.first}-{args.first + args.count - 1}): size error median "
          f"{size_all['median']} mm (p95 {size_all['p95']}; band {bands['size_p95_mm']}), location error median "
          f"{location_all['median']} mm (p95 {location_all['p95']}; band {bands['loc_p95_mm']}); "
          f"{result['kitchens_within_bands']} of {len(rows)} kitchens within the bands on their own; pointing "
          f"{pointed - missed}/{pointed} reached, {len(touched)} room contacts; pick-and-place {successes}/{attempts}; "
          f"{result['wall_seconds']} s")
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
