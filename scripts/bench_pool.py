"""Wall time of a suite on several data seeds with one pool of workers for all of them, against a fresh pool per
data seed, in one run (issue 54 item 3: ``make experiments`` keeps both cores busy between data seeds).

Both sides run ``teachbot regress --suite SUITE --data-seeds ...`` in a subprocess of the same code. The
reference replaces ``regress.shared_pool`` with one that yields no pool, so each data seed runs as it did before
``EpisodePool`` (its own 2-worker pool, and the report written while no episode runs); the measured side is the
command as shipped. The sides alternate round by round; the figures are wall seconds, the cores kept busy
(CPU seconds of the subprocess and its workers over wall seconds) and the ratio of wall times. Both sides write
byte-identical transcripts (checked). Run it on an otherwise idle machine.

    python scripts/bench_pool.py --json                          # ch6-static on data seeds 0-4
    python scripts/bench_pool.py --suite ch7 --data-seeds 0 1 --strategies dt-task active --json
"""

from __future__ import annotations

import argparse
import filecmp
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

DRIVER = r"""
import contextlib, sys
import dialog.commands.regress as regress
from dialog.cli import main
if sys.argv[1] == "fresh-pools":
    @contextlib.contextmanager
    def no_shared_pool(args):
        yield None
    regress.shared_pool = no_shared_pool
sys.exit(main(sys.argv[2:]))
"""


def side(name: str, suite: str, seeds: list[int], strategies: list[str] | None, out: Path) -> dict:
    command = [sys.executable, "-c", DRIVER, name, "regress", "--suite", suite, "--data-seeds", *map(str, seeds),
               "--results", str(out), "--no-progress"] + (["--strategies", *strategies] if strategies else [])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(command, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": round(wall, 2), "cpu_s": round(cpu, 2), "cores_busy": round(cpu / wall, 3)}


def same_transcripts(a: Path, b: Path) -> bool:
    files = sorted(p.relative_to(a) for p in a.rglob("*.jsonl"))
    return bool(files) and files == sorted(p.relative_to(b) for p in b.rglob("*.jsonl")) and all(
        filecmp.cmp(a / f, b / f, shallow=False) for f in files)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", default="ch6-static")
    parser.add_argument("--data-seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--strategies", nargs="+", default=None)
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    runs: dict[str, list[dict]] = {"fresh-pools": [], "one-pool": []}
    with tempfile.TemporaryDirectory(prefix="bench-pool-") as folder:
        for round_ in range(args.rounds):
            order = ("fresh-pools", "one-pool") if round_ % 2 == 0 else ("one-pool", "fresh-pools")
            for name in order:
                runs[name].append(side(name, args.suite, args.data_seeds, args.strategies,
                                       Path(folder) / f"{name}-{round_}"))
                print(f"round {round_ + 1} {name}: {runs[name][-1]}", flush=True)
        identical = same_transcripts(Path(folder) / "fresh-pools-0", Path(folder) / "one-pool-0")
    wall = {name: sum(r["wall_s"] for r in rs) for name, rs in runs.items()}
    busy = {name: round(sum(r["cpu_s"] for r in rs) / wall[name], 3) for name, rs in runs.items()}
    ratio = wall["fresh-pools"] / wall["one-pool"]
    print(f"{args.suite} on data seeds {' '.join(map(str, args.data_seeds))}: fresh pools {wall['fresh-pools']:.1f} s "
          f"({busy['fresh-pools']:.2f} cores busy), one pool {wall['one-pool']:.1f} s ({busy['one-pool']:.2f}); "
          f"one pool is {ratio:.3f}x as fast; transcripts identical: {identical}")
    if args.json:
        print(json.dumps({"suite": args.suite, "data_seeds": args.data_seeds, "strategies": args.strategies,
                          "rounds": runs, "wall_s": wall, "cores_busy": busy, "speedup": round(ratio, 3),
                          "transcripts_identical": identical}))
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
