"""Measure how long the Panda takes to point at an object, and fit seconds = f(distance, bearing).

    python scripts/fit_motion_time.py                        # print the fit; nothing written
    python scripts/fit_motion_time.py --write                # also write dialog/data/pointing-time.toml
    python scripts/fit_motion_time.py --scenes 2 --json      # fewer scenes; JSON last line

For every kitchen and task, a few scenes are built in PyBullet (DIRECT, physics on); for every object the
arm rests, then really points at it (``robot.gestures.point_at`` at the joint speed of
``dialog/data/embodied-costs.toml``) and the simulated seconds of the motion are recorded with the object's
measured ``location.robot.distance`` and ``location.robot.bearing`` (the features every data-set row has).
The model is non-negative least squares on a few terms of distance d and |bearing| b
(1, d, b, d^2, b^2, d*b): every coefficient >= 0, so a farther object, or one further to the side, never
takes less. Within a scene the arm does not rest between gestures, so after each pointing from rest it
also points at a random other object of the scene, and a second model of the same form is fitted on the
absolute differences of the two objects' distances and bearings (pointing from the previous object).
Residuals are reported on the fitted points and on a held-out kitchen (each kitchen left
out in turn). The arm also fetches a few examples from each kitchen's pantry; their mean seconds go in
the file too. The file records its provenance: commit, kitchens, tasks, seeds, n, residual error.
"""

from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import nnls

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bullet_world.datafiles import available  # noqa: E402
from dialog.embodied import BEARING, COSTS_FILE, DISTANCE, POINTING_FILE, TERMS, term_matrix  # noqa: E402
from learning.datafiles import read_toml  # noqa: E402

DEFAULT_TASKS = ("pack-lunchbox", "prepare-lunch")


def measure(tasks, kitchens, seeds, joint_speed: float, fetches: int) -> tuple[list[dict], list[dict], list[float]]:
    """Pointing times of every object of every scene from rest, the same from the previously pointed object
    (object i, then a random other object j, as the arm goes within a scene), and a few pantry fetches."""
    from dialog.environment import SimulatedKitchen
    from robot.gestures import point_at

    rows, onward, fetched = [], [], []
    for kitchen in kitchens:
        for task in tasks:
            env = SimulatedKitchen(task=task, kitchen=kitchen, seed=0, joint_speed=joint_speed)
            try:
                names = list(env.feature_names)
                d, b = names.index(DISTANCE), names.index(BEARING)
                for seed in seeds:
                    rng = np.random.default_rng(seed)
                    env.arm.rest()
                    scene = env.world.new_scene(rng)
                    for i in range(scene.n_objects):
                        env.arm.rest()
                        result = point_at(env.arm, scene.positions[i], scene.tops[i], joint_speed)
                        rows.append({"kitchen": kitchen, "task": task, "seed": seed, "object": i,
                                     "distance": float(scene.X[i, d]), "bearing": float(scene.X[i, b]),
                                     "seconds": result.sim_seconds, "reached": bool(result.reached)})
                        j = int(rng.choice([k for k in range(scene.n_objects) if k != i]))
                        result = point_at(env.arm, scene.positions[j], scene.tops[j], joint_speed)
                        onward.append({"kitchen": kitchen, "task": task, "seed": seed, "object": j,
                                       "distance": abs(float(scene.X[j, d] - scene.X[i, d])),
                                       "bearing": abs(float(scene.X[j, b] - scene.X[i, b])),
                                       "seconds": result.sim_seconds, "reached": bool(result.reached)})
                    env.arm.rest()
                    for k in range(fetches if task == tasks[0] else 0):
                        concept = env.concepts[k % len(env.concepts)]
                        if env.can_fetch(concept):
                            got = env.fetch(scene, concept, rng) or {}
                            if "sim_seconds" in got:
                                fetched.append(float(got["sim_seconds"]))
                        env.arm.rest()
            finally:
                env.close()
    return rows, onward, fetched


def summarise_fit(rows: list[dict], kitchens, terms) -> dict:
    """The non-negative least-squares fit on ``rows`` and its residuals (leave-one-kitchen-out too)."""
    coefficients = fit(rows, terms)
    res = residuals(rows, terms, coefficients)
    seconds = np.array([r["seconds"] for r in rows])
    held = []
    for kitchen in kitchens:
        train = [r for r in rows if r["kitchen"] != kitchen]
        test = [r for r in rows if r["kitchen"] == kitchen]
        if train and test:
            held.append(residuals(test, terms, fit(train, terms)))
    distances, bearings = [r["distance"] for r in rows], [abs(r["bearing"]) for r in rows]
    return {"terms": list(terms), "coefficients": [float(c) for c in coefficients],
            "distance_range": [float(min(distances)), float(max(distances))],
            "bearing_range": [float(min(bearings)), float(max(bearings))],
            "rms": float(np.sqrt(np.mean(res ** 2))), "max_abs": float(np.max(np.abs(res))),
            "r2": float(1 - np.sum(res ** 2) / np.sum((seconds - seconds.mean()) ** 2)),
            "held_out_rms": float(np.sqrt(np.mean(np.concatenate(held) ** 2))) if held else float("nan"),
            "n": len(rows), "seconds_range": [float(seconds.min()), float(seconds.max())],
            "mean_seconds": float(seconds.mean())}


def fit(rows: list[dict], terms) -> np.ndarray:
    A = term_matrix(terms, [r["distance"] for r in rows], [abs(r["bearing"]) for r in rows])
    coefficients, _ = nnls(A, np.array([r["seconds"] for r in rows]))
    return coefficients


def residuals(rows: list[dict], terms, coefficients) -> np.ndarray:
    A = term_matrix(terms, [r["distance"] for r in rows], [abs(r["bearing"]) for r in rows])
    return np.array([r["seconds"] for r in rows]) - A @ coefficients


def commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True)
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "robot", "bullet_world", "dialog/environment.py"],
                               cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
        return out.stdout.strip() + ("+uncommitted robot/world changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def toml_file(summary: dict) -> str:
    def array(values, digits=6):
        return "[" + ", ".join(f"{v:.{digits}g}" if isinstance(v, float) else json.dumps(v) for v in values) + "]"

    def table(name: str, fit_: dict) -> str:
        return f"""[{name}]
terms = {array(fit_["terms"])}
coefficients = {array(fit_["coefficients"])}
distance_range = {array(fit_["distance_range"], 4)}
bearing_range = {array(fit_["bearing_range"], 4)}
joint_speed = {summary["joint_speed"]:g}
n = {fit_["n"]}
seconds_range = {array(fit_["seconds_range"], 4)}
rms_residual_seconds = {fit_["rms"]:.4g}
max_abs_residual_seconds = {fit_["max_abs"]:.4g}
r_squared = {fit_["r2"]:.4g}
held_out_kitchen_rms_seconds = {fit_["held_out_rms"]:.4g}
"""

    return f"""# The Panda's pointing time, measured in the simulation: seconds = sum_k coefficients[k] * term_k,
# both inputs clipped to the measured ranges. Written by scripts/fit_motion_time.py --write
# (non-negative least squares); do not edit by hand, refit. Read by dialog/embodied.py. The arm
# points with robot.gestures.point_at at joint_speed rad/s, as dialog/data/embodied-costs.toml sets it.
#
# [model]: from rest (the first pointing in a scene; the arm rests whenever the scene changes);
#   distance = location.robot.distance (m), bearing = |location.robot.bearing| (rad) of the object.
# [from_previous]: from above the object pointed at last in the same scene; distance and bearing are
#   the absolute differences between the two objects' distances and bearings to the robot.

{table("model", summary["fit"])}
{table("from_previous", summary["from_previous"])}
[fetch]
# a pantry fetch's simulated seconds (the reach over the pantry; scene objects to the side make it longer)
mean_seconds = {summary["fetch"]["mean_seconds"]:.4g}
sd_seconds = {summary["fetch"]["sd_seconds"]:.4g}
n = {summary["fetch"]["n"]}

[provenance]
script = "scripts/fit_motion_time.py"
commit = "{summary["commit"]}"
measured = "{summary["measured"]}"
kitchens = {array(summary["kitchens"])}
tasks = {array(summary["tasks"])}
seeds = {array(summary["seeds"])}
motions = {summary["n"]}
reached = {summary["reached"]}
"""


def _report(name: str, f: dict) -> None:
    print(f"{name}: {f['n']} motions, {f['seconds_range'][0]:.2f}-{f['seconds_range'][1]:.2f} s (mean "
          f"{f['mean_seconds']:.2f}); inputs {f['distance_range'][0]:.2f}-{f['distance_range'][1]:.2f} m, "
          f"{f['bearing_range'][0]:.2f}-{f['bearing_range'][1]:.2f} rad")
    print("  fit: " + " + ".join(f"{c:.3f}*{t}" for c, t in zip(f["coefficients"], f["terms"]) if c > 0))
    print(f"  residual rms {f['rms']:.3f} s, max {f['max_abs']:.3f} s, R^2 {f['r2']:.3f}; "
          f"leave-one-kitchen-out rms {f['held_out_rms']:.3f} s")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kitchens", nargs="+", default=None, help="kitchens (default: all)")
    parser.add_argument("--tasks", nargs="+", default=list(DEFAULT_TASKS), help="tasks whose scenes are used")
    parser.add_argument("--scenes", type=int, default=3, help="scenes per kitchen and task (seeds 0..N-1)")
    parser.add_argument("--fetches", type=int, default=4, help="pantry fetches per kitchen and scene")
    parser.add_argument("--write", action="store_true", help=f"write {POINTING_FILE.relative_to(ROOT)}")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    kitchens = args.kitchens or available("kitchens")
    seeds = list(range(args.scenes))
    joint_speed = float(read_toml(COSTS_FILE, "embodied costs")["arm"]["joint_speed"])
    started = time.perf_counter()
    rows, onward, fetched = measure(args.tasks, kitchens, seeds, joint_speed, args.fetches)
    wall = time.perf_counter() - started
    terms = tuple(TERMS)
    summary = {
        "n": len(rows) + len(onward), "reached": int(sum(r["reached"] for r in rows + onward)),
        "kitchens": list(kitchens), "tasks": list(args.tasks), "seeds": seeds, "joint_speed": joint_speed,
        "commit": commit(), "measured": datetime.date.today().isoformat(), "wall_seconds": round(wall, 1),
        "fit": summarise_fit(rows, kitchens, terms), "from_previous": summarise_fit(onward, kitchens, terms),
        "fetch": {"n": len(fetched), "mean_seconds": float(np.mean(fetched)) if fetched else 0.0,
                  "sd_seconds": float(np.std(fetched)) if fetched else 0.0},
    }
    print(f"{summary['n']} pointing motions ({summary['reached']} reached) in {len(kitchens)} kitchens x "
          f"{len(args.tasks)} tasks x {len(seeds)} scenes at {joint_speed:g} rad/s; {wall:.0f} s wall time")
    _report("from rest", summary["fit"])
    _report("from the previous object", summary["from_previous"])
    print(f"pantry fetch: {summary['fetch']['n']} fetches, mean {summary['fetch']['mean_seconds']:.2f} s "
          f"(sd {summary['fetch']['sd_seconds']:.2f})")
    if args.write:
        POINTING_FILE.write_text(toml_file(summary))
        print(f"written {POINTING_FILE.relative_to(ROOT)}")
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
