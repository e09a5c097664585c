"""Benchmark: what the limits of learning/data/limits.toml cost on this machine, against the demo's own size.

    python scripts/bench_limits.py            # the library's dt-task turn at the concept and scene limits
    python scripts/bench_limits.py --json     # the figures, then one JSON line
    python scripts/bench_limits.py --episode  # also a demo episode at the turn limit (some minutes)

Each case runs in its own process, so its peak resident memory is its own. The reference, measured in the
same run, is the demo's size: 4 concepts, 12 objects per scene (and a 30-turn demo episode). The machine's
budget the limits are sized for: 24 GiB of memory and a day (86,400 s) for one run.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

MACHINE_BYTES = 24 * 2**30
DAY_SECONDS = 86_400
FEATURES = 86  # the kitchen's feature catalogue
TURNS = 3  # dt-task turns timed per case


def library_turn(concepts: int, objects: int) -> dict:
    """Seconds per dt-task turn (ask + tell) of TeachingLoop on one scene, and this process's peak memory."""
    from learning import TeachingLoop

    rng = np.random.default_rng(0)
    centres = rng.normal(0, 3, (concepts, FEATURES))
    truth = np.arange(objects) % concepts
    loop = TeachingLoop(list(range(concepts)), strategy="dt-task", budget=40, turns=30, seed=0)
    started = time.perf_counter()
    loop.observe(centres[truth] + rng.normal(0, 1, (objects, FEATURES)))
    for _ in range(TURNS):
        query = loop.ask()
        if query.kind == "label":
            loop.tell(int(truth[query.object]))
        elif query.kind == "demo":
            loop.tell(int(np.flatnonzero(truth == query.concept)[0]))
        else:
            loop.tell(None)
    return {"concepts": concepts, "objects": objects, "seconds_per_turn": (time.perf_counter() - started) / TURNS,
            "peak_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}


def demo_episode(turns: int) -> dict:
    """A demo episode of ``turns`` turns (the default budget of 40), its wall time and peak memory."""
    import tempfile

    from dialog.cli import main

    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        code = main(["demo", "--turns", str(turns), "--transcript", f"{folder}/t.jsonl"])
        seconds = time.perf_counter() - started
    return {"turns": turns, "exit": code, "seconds": seconds,
            "peak_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}


def in_own_process(case: str, *numbers: int) -> dict:
    """Run one case in a fresh interpreter (its own peak memory); its last stdout line is the JSON result."""
    done = subprocess.run([sys.executable, __file__, "--case", case, *map(str, numbers)], check=True,
                          capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line of the figures")
    parser.add_argument("--episode", action="store_true", help="also a demo episode at the turn limit")
    parser.add_argument("--case", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        kind, *numbers = args.case
        result = library_turn(*map(int, numbers)) if kind == "library" else demo_episode(int(numbers[0]))
        print(json.dumps(result))
        return 0
    from learning.limits import maximum

    rows = [("reference", in_own_process("library", 4, 12)),
            ("at the limits", in_own_process("library", maximum("concepts"), maximum("scene_objects")))]
    if args.episode:
        rows += [("reference episode", in_own_process("episode", 30)),
                 ("episode at the turn limit", in_own_process("episode", maximum("turns")))]
    for name, row in rows:
        size = (f"{row['concepts']} concepts x {row['objects']} objects: {row['seconds_per_turn']:.2f} s a dt-task turn"
                if "concepts" in row else f"demo of {row['turns']} turns: {row['seconds']:.1f} s")
        print(f"{name:>26}: {size}, peak {row['peak_bytes'] / 2**30:.2f} GiB "
              f"({row['peak_bytes'] / MACHINE_BYTES:.1%} of 24 GiB)")
    if args.json:
        print(json.dumps({"machine_bytes": MACHINE_BYTES, "day_seconds": DAY_SECONDS,
                          "cases": [{"name": name, **row} for name, row in rows]}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
