"""Time `teachbot learn-weights` by each method, with `teachbot --help` (start-up) as the reference in the same run.

Rows, each the whole command as a subprocess on the shipped demonstrations (docs/irl.md):
- imitation (the default): the issue-27 protocol, 3 splits x 5 fit seeds x 2 policy forms of per-turn MaxEnt;
- per-turn: one per-turn MaxEnt fit;
- trajectory, --select likelihood (the default) and --select accuracy (the criterion before issue 27): eq. 7.7
  with rollouts of the real dialog loop in the training condition (goal: <= 10 min for one fit with rollouts).
Beside each: the kept iterate and, from the written weights' provenance, its held-out imitation and validation
accuracy. The last line is JSON with --json.

    .venv/bin/python scripts/bench_irl.py [--iterations 100] [--skip-trajectory] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import tomllib

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))


def timed(command: list[str]) -> tuple[float, float]:
    """(wall seconds, CPU seconds of the child) of one command, which must succeed."""
    before = os.times()
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - started
    after = os.times()
    if done.returncode != 0:
        sys.exit(f"bench_irl: {' '.join(command)} failed:\n{done.stderr}")
    return wall, (after.children_user - before.children_user) + (after.children_system - before.children_system)


def provenance(path: Path) -> dict:
    with path.open("rb") as handle:
        return tomllib.load(handle).get("provenance", {})


def row(name: str, options: list[str], scratch: Path) -> dict:
    out = scratch / f"{name}.toml"
    wall, cpu = timed([TEACHBOT, "learn-weights", "--demos", "shipped", "--out", str(out), *options])
    p = provenance(out)
    picked = {key: p.get(key) for key in ("best_iteration", "held_out_agreement", "held_out_exact_agreement",
                                          "held_out_ask_or_quiet_agreement", "held_out_log_likelihood",
                                          "validation_accuracy", "select_by", "select_iterate_by")
              if key in p}
    return {"method": name, "options": " ".join(options), "wall_seconds": round(wall, 2),
            "cpu_seconds": round(cpu, 2), **picked}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=100, help="trajectory iterations (default 100, as shipped)")
    parser.add_argument("--skip-trajectory", action="store_true", help="time the per-turn methods only")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    startup, _ = timed([TEACHBOT, "--help"])
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        rows.append(row("imitation", [], Path(scratch)))
        rows.append(row("per-turn", ["--method", "per-turn"], Path(scratch)))
        if not args.skip_trajectory:
            for select in ("likelihood", "accuracy"):
                rows.append(row(f"trajectory-{select}", ["--method", "trajectory", "--iterations",
                                                         str(args.iterations), "--select", select], Path(scratch)))
    print(f"teachbot --help (start-up): {startup:.2f} s")
    for r in rows:
        scores = ", ".join(f"{k} {v}" for k, v in r.items()
                           if k not in ("method", "options", "wall_seconds", "cpu_seconds"))
        print(f"{r['method']:<22} {r['wall_seconds']:>8.1f} s wall, {r['cpu_seconds']:>8.1f} s CPU"
              f" ({r['wall_seconds'] / startup:.0f}x start-up); {scores}")
    if args.json:
        print(json.dumps({"startup_seconds": round(startup, 3), "rows": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
