"""How long a dt-voi decision takes as its pool grows: CPU time of ``voi_gains`` and its two engine calls.

Seeded synthetic states at bench_decision's stress point by default (|Y| 4, |F| 90, ``--objects`` 55,
``--train`` 150, the feature question open; ``learning.synthetic.random_state``), each with a pool of
``--pools`` earlier objects drawn from the same task. One BLAS thread, CPU time of this process.

    python scripts/bench_voi.py --pools 0 50 200 --json     # last line: one JSON object
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from learning.decision.voi import voi_gains  # noqa: E402
from learning.synthetic import SyntheticTask, random_state  # noqa: E402
from learning.whatif.fast import feature_outcomes, pair_table  # noqa: E402


def _cpu_ms(function, *arguments) -> float:
    start = time.process_time()
    function(*arguments)
    return 1000.0 * (time.process_time() - start)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pools", type=int, nargs="+", default=[0, 50, 200])
    parser.add_argument("--objects", type=int, default=55)
    parser.add_argument("--train", type=int, default=150)
    parser.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102, 103, 104])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if min(args.pools) < 0 or args.objects < 1 or args.train < 0:
        parser.error("--pools must be >= 0, --objects >= 1 and --train >= 0")
    task = SyntheticTask(seed=args.seeds[0])
    rows = []
    for size in args.pools:
        timings = {"voi_gains": [], "pair_table": [], "feature_outcomes": []}
        for seed in args.seeds:
            rng = np.random.default_rng(seed)
            state = random_state(task, args.train, args.objects, rng)
            pool = task.sample(size, rng)[0] if size else None
            timings["pair_table"].append(_cpu_ms(pair_table, state, pool))
            timings["feature_outcomes"].append(_cpu_ms(feature_outcomes, state, pool))
            timings["voi_gains"].append(_cpu_ms(voi_gains, state, pool))
        row = {"pool": size, **{k: round(float(np.median(v)), 1) for k, v in timings.items()},
               "voi_gains_max": round(float(np.max(timings["voi_gains"])), 1)}
        rows.append(row)
        print(f"pool {size:4d}: voi_gains p50 {row['voi_gains']:7.1f} ms (max {row['voi_gains_max']:.1f}), "
              f"pair_table {row['pair_table']:.1f} ms, feature_outcomes {row['feature_outcomes']:.1f} ms", flush=True)
    if args.json:
        print(json.dumps({"settings": vars(args), "results": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
