"""Time `teachbot learn-weights --demos shipped` against references measured in the same run.

Figures: the whole command as a subprocess (interpreter start-up included), learn_weights in-process (load,
split, fit), loading the shipped demonstrations alone, and `teachbot --help` (the start-up reference); plus the
validation agreement. The last line is JSON with --json.

    .venv/bin/python scripts/bench_irl.py [--repeats 3] [--json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from learning.irl.learn import learn_weights, load_demonstrations  # noqa: E402

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))


def best_of(repeats: int, work) -> float:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        work()
        times.append(time.perf_counter() - started)
    return min(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "w.toml"
        command = best_of(args.repeats, lambda: subprocess.run(
            [TEACHBOT, "learn-weights", "--demos", "shipped", "--out", str(out)], check=True, capture_output=True))
    startup = best_of(args.repeats, lambda: subprocess.run([TEACHBOT, "--help"], check=True, capture_output=True))
    learn_weights("shipped")  # first call imports torch
    in_process = best_of(args.repeats, lambda: learn_weights("shipped"))
    loading = best_of(args.repeats, lambda: load_demonstrations("shipped"))
    learned = learn_weights("shipped")
    figures = {"command_seconds": round(command, 3), "startup_seconds": round(startup, 3),
               "learn_in_process_seconds": round(in_process, 4), "fit_seconds": round(learned.result.seconds, 4),
               "load_seconds": round(loading, 4), "iterations": learned.result.iterations,
               "train_turns": learned.result.train_turns, "validation_turns": learned.result.validation_turns,
               "validation_agreement": learned.result.validation_agreement,
               "validation_ask_or_quiet_agreement": learned.weights.provenance.get(
                   "validation_ask_or_quiet_agreement")}
    print(f"teachbot learn-weights --demos shipped: {command:.2f} s (teachbot --help: {startup:.2f} s; limit 60 s)")
    print(f"in process: {in_process:.3f} s = loading {loading:.3f} s + fit {learned.result.seconds:.3f} s "
          f"({learned.result.iterations} iterations, {learned.result.train_turns} training turns)")
    print(f"validation agreement {learned.result.validation_agreement:.3f} on {learned.result.validation_turns} turns")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
