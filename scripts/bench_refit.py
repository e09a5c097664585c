"""Refit after one answer: the incremental Laplace update against a fresh fit, per concept model, n = 50 ... 2000.

For every training-set size n, a concept model (``learning.gp.BinaryGPClassifier``,
the learner's kernel: RBF with length scale sqrt(|F|), variance 4) is fitted on
n - 1 standardised rows of the synthetic task (|F| = 90, 6 informative, the
concept "fruit" against the rest); then the n-th row arrives, as after one
answer, and is learned twice, each from the same n - 1 fit:

* incremental: ``fit(X, y, previous=...)``, the old kernel block reused and
  Newton started from the old mode (chord steps with the old factor bordered
  by the new row, then the single-precision factor at the new mode), forced at every n
  (``incremental_from=1``) so the rows show the update itself;
* fresh: ``fit(X, y)`` from scratch, what every refit did before.

Both are CPU time (``time.process_time``) with one BLAS thread (threadpoolctl),
the median of ``--repeats`` answers (each a different n-th row); ``max_dp`` is
the largest difference of their predictive probabilities on 200 held-out rows
(the equality the tests demand is 1e-6, the Newton tolerance). The growth
exponents are least-squares slopes of log time on log n over the sizes from
500 to 2000.

    python scripts/bench_refit.py --json      # last line: {"rows": [...], "incremental_exponent", "fresh_exponent"}
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np
from threadpoolctl import threadpool_limits

from learning.gp import INCREMENTAL_FROM, BinaryGPClassifier
from learning.synthetic import SyntheticTask

SIZES = (50, 100, 200, 500, 1000, 1500, 2000)
EXPONENT_SIZES = (500, 2000)  # the exponents are fitted over the sizes in this range
HELD_OUT = 200


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="training-set sizes n")
    parser.add_argument("--repeats", type=int, default=3, help="answers timed per size, median kept (default 3)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if args.repeats < 1 or min(args.sizes) < 2:
        parser.error("--repeats must be at least 1 and every size at least 2")
    return args


def cpu_ms(work) -> tuple[float, object]:
    started = time.process_time()
    result = work()
    return 1e3 * (time.process_time() - started), result


def measure(n: int, X: np.ndarray, y: np.ndarray, held_out: np.ndarray, repeats: int) -> dict:
    incremental, fresh, max_dp = [], [], 0.0
    for r in range(repeats):
        rows = np.r_[0 : n - 1, n - 1 + r]  # the n - 1 known rows, then answer r's row
        X_n, y_n = X[rows], y[rows]
        before = BinaryGPClassifier(incremental_from=1).fit(X_n[:-1], y_n[:-1])
        ms, updated = cpu_ms(lambda: BinaryGPClassifier(incremental_from=1).fit(X_n, y_n, previous=before))  # noqa: B023
        assert updated.incremental_, "the answer only adds a row: the update path must run"
        incremental.append(ms)
        ms, refitted = cpu_ms(lambda: BinaryGPClassifier().fit(X_n, y_n))  # noqa: B023
        fresh.append(ms)
        max_dp = max(max_dp, float(np.max(np.abs(updated.predict_proba(held_out) - refitted.predict_proba(held_out)))))
    return {"n": n, "incremental_ms": round(float(np.median(incremental)), 2),
            "fresh_ms": round(float(np.median(fresh)), 2), "max_dp": float(f"{max_dp:.3g}")}


def exponent(rows: list[dict], key: str) -> float | None:
    chosen = [r for r in rows if EXPONENT_SIZES[0] <= r["n"] <= EXPONENT_SIZES[1]]
    if len(chosen) < 2:
        return None
    slope = np.polyfit(np.log([r["n"] for r in chosen]), np.log([r[key] for r in chosen]), 1)[0]
    return round(float(slope), 2)


def main(args) -> int:
    task = SyntheticTask(seed=args.seed)
    rng = np.random.default_rng(args.seed)
    X, labels = task.sample(max(args.sizes) + args.repeats + HELD_OUT, rng)
    X = (X - X.mean(axis=0)) / X.std(axis=0)
    y = labels == "fruit"
    held_out, X, y = X[-HELD_OUT:], X[:-HELD_OUT], y[:-HELD_OUT]
    print(f"refit after one answer, |F| = {task.n_features}, one BLAS thread, CPU ms (median of {args.repeats}); "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs; the learner updates from "
          f"n = {INCREMENTAL_FROM} (below, a fresh fit is cheaper)")
    print(f"{'n':>5} | {'incremental':>11} | {'fresh':>9} | {'speedup':>7} | {'max |dp|':>8}")
    rows = []
    with threadpool_limits(limits=1, user_api="blas"):
        for n in sorted(args.sizes):
            row = measure(n, X, y, held_out, args.repeats)
            rows.append(row)
            print(f"{n:>5} | {row['incremental_ms']:>9.2f}ms | {row['fresh_ms']:>7.2f}ms | "
                  f"{row['fresh_ms'] / max(row['incremental_ms'], 1e-9):>6.1f}x | {row['max_dp']:>8.1e}", flush=True)
    result = {"rows": [{k: r[k] for k in ("n", "incremental_ms", "fresh_ms")} for r in rows],
              "incremental_exponent": exponent(rows, "incremental_ms"), "fresh_exponent": exponent(rows, "fresh_ms")}
    print(f"growth exponent over n {EXPONENT_SIZES[0]}-{EXPONENT_SIZES[1]}: incremental "
          f"{result['incremental_exponent']}, fresh {result['fresh_exponent']}; largest |dp| "
          f"{max(r['max_dp'] for r in rows):.1e}")
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(_parse(sys.argv[1:])))
