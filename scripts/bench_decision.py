"""Interaction-time benchmark of the decision-theoretic choice: fast what-if engine vs the brute-force reference.

Both engines score every candidate action (|Y| demos, |X| labels, the feature
query when it is still open, no query), each at its own next state (eq. 7.1),
of the same seeded learning states and the DT rule picks one. States come from
``learning.synthetic.random_state``: |Y| = 4 concepts, |F| = 90 features of
which 6 are informative, a scene of |X| objects, n_train labelled examples
with uneven classes, some budget spent and a random recent history; in about
half of them the teacher has already answered the feature query.

Timing: the decision only (expected decision features of every candidate +
argmax); the learner's current p(y|x) is part of the state and computed
before the clock starts. Each fast timing is the best of ``--repeats`` cold
runs (the state's cache cleared before each); the reference is timed once.
BLAS runs on one thread unless ``--threads`` says otherwise. The CPU times are
also split by whether the feature query is still open (``fast_cpu_ms_fsq_closed``
and ``_open``), and on the open states ES alone, the teacher's simulated answer
F_{y,c}, is timed too (``es_cpu_ms``, best of as many cold runs): the floors of
a decision. One more cold run per state, not timed as a whole, adds up the CPU time spent inside the
LAPACK calls the engine makes (``lapack_cpu_ms_fsq_closed`` / ``_open``, f2py's wrapper included; see
``lapack_timer``): what a compiled port of the same algorithm would still pay.
``fast_ms`` and ``reference_ms`` are wall-clock; ``fast_cpu_ms`` and ``reference_cpu_ms`` are
this process's CPU time for the same runs, which other programs on a busy
machine do not inflate (``speedup_cpu`` compares those); the load average at
the start and end is printed and reported.

    python scripts/bench_decision.py --json        # last line: one JSON object per size
"""

from __future__ import annotations

import argparse
import os
import sys


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=40, help="seeded states per size (default 40)")
    parser.add_argument("--reference-states-large", type=int, default=6,
                        help="states per size that also run the reference when n_train >= 500 (default 6)")
    parser.add_argument("--objects", type=int, nargs="+", default=[12, 55], help="scene sizes |X| (default 12 55)")
    parser.add_argument("--train", type=int, nargs="+", default=[20, 150, 500],
                        help="training-set sizes (default 20 150 500)")
    parser.add_argument("--weights", default="dt", help="DT weights: preset name or TOML path")
    parser.add_argument("--repeats", type=int, default=5, help="cold runs per fast timing, best kept (default 5)")
    parser.add_argument("--threads", type=int, default=1, help="BLAS threads (default 1)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--profile", type=int, default=0, metavar="N",
                        help="also print cProfile's top N entries (cumulative) of the fast decisions, per size")
    parser.add_argument("--json", action="store_true", help="end with one JSON line (a list, one object per size)")
    args = parser.parse_args(argv)
    for name in ("states", "reference_states_large", "repeats", "threads"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be at least 1, got {getattr(args, name)}")
    return args


ARGS = _parse(sys.argv[1:]) if __name__ == "__main__" else None
if ARGS is not None:  # BLAS reads these once, when numpy is first imported
    for variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[variable] = str(ARGS.threads)

import json  # noqa: E402
import time  # noqa: E402
from contextlib import contextmanager  # noqa: E402

import numpy as np  # noqa: E402

from learning.decision.candidates import expected_decision_features  # noqa: E402
from learning.decision.weights import resolve_weights  # noqa: E402
from learning.strategies.decision_theoretic import choose_index  # noqa: E402
from learning.synthetic import SyntheticTask, random_state  # noqa: E402
from learning.whatif.base import feature_query_subsets  # noqa: E402

LARGE_TRAINING_SET = 500


def decide(state, engine: str, weights: np.ndarray):
    candidates = expected_decision_features(state, engine)
    utilities = candidates.utilities(weights)
    return candidates, utilities, choose_index(utilities)


@contextmanager
def lapack_timer():
    """Add up the CPU seconds spent inside the what-if engine's LAPACK calls while the block runs.

    Yields a one-element list holding the running total. The engine's factorisations and solves are the
    ``spotrf``, ``spotrs`` and ``strtrs`` that ``learning.whatif.laplace`` and ``learning.gp`` import and the small
    batched ``numpy.linalg.solve`` of the weight-space Newton; each name is wrapped for the block only.
    Matrix products and elementwise work are not counted: this is a lower bound on a compiled port's time.
    """
    import learning.gp as gp
    import learning.whatif.laplace as laplace

    total = [0.0]
    targets = [(module, name) for module in (gp, laplace) for name in ("spotrf", "spotrs", "strtrs")
               if hasattr(module, name)]
    targets.append((np.linalg, "solve"))
    originals = [getattr(module, name) for module, name in targets]

    def timed(function):
        def call(*args, **kwargs):
            started = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                total[0] += time.process_time() - started
        return call

    for (module, name), original in zip(targets, originals):
        setattr(module, name, timed(original))
    try:
        yield total
    finally:
        for (module, name), original in zip(targets, originals):
            setattr(module, name, original)


def print_profile(states, weights: np.ndarray, top: int) -> None:
    """cProfile of one cold fast decision per state, the ``top`` entries by cumulative time."""
    import cProfile
    import pstats

    profiler = cProfile.Profile()
    for state in states:
        state.cache.clear()
        profiler.enable()
        decide(state, "fast", weights)
        profiler.disable()
    pstats.Stats(profiler, stream=sys.stdout).sort_stats("cumulative").print_stats(top)


def measure_size(n_objects: int, n_train: int, args, weights: np.ndarray) -> dict:
    task = SyntheticTask(seed=args.seed)
    rng = np.random.default_rng([args.seed, n_objects, n_train])
    with_reference = args.states if n_train < LARGE_TRAINING_SET else min(args.states, args.reference_states_large)
    fast_ms, fast_cpu_ms, reference_ms, reference_cpu_ms = [], [], [], []
    same, regrets, eu_errors, states_seen = [], [], [], []
    by_fsq: dict[bool, list[float]] = {True: [], False: []}
    es_cpu_ms = []
    lapack_ms: dict[bool, list[float]] = {True: [], False: []}
    for index in range(args.states):
        state = random_state(task, n_train, n_objects, rng, feature_query_answered=bool(rng.random() < 0.5))
        state.probabilities()  # the learner's current beliefs belong to the state, not to the decision
        states_seen.append(state)
        best, best_cpu = np.inf, np.inf
        for _ in range(args.repeats):
            state.cache.clear()
            started, started_cpu = time.perf_counter(), time.process_time()
            candidates, fast_utilities, fast_choice = decide(state, "fast", weights)
            best = min(best, time.perf_counter() - started)
            best_cpu = min(best_cpu, time.process_time() - started_cpu)
        fast_ms.append(1e3 * best)
        fast_cpu_ms.append(1e3 * best_cpu)
        by_fsq[not state.feature_query_asked].append(1e3 * best_cpu)
        state.cache.clear()
        with lapack_timer() as inside:
            decide(state, "fast", weights)
        lapack_ms[not state.feature_query_asked].append(1e3 * inside[0])
        if not state.feature_query_asked:
            es_cpu_ms.append(1e3 * _best_cpu_seconds(lambda s=state: feature_query_subsets(s), args.repeats))
        if index >= with_reference:
            continue
        started, started_cpu = time.perf_counter(), time.process_time()
        reference, reference_utilities, reference_choice = decide(state, "reference", weights)
        reference_ms.append(1e3 * (time.perf_counter() - started))
        reference_cpu_ms.append(1e3 * (time.process_time() - started_cpu))
        assert reference.actions == candidates.actions
        same.append(fast_choice == reference_choice)
        regrets.append(float(reference_utilities[reference_choice] - reference_utilities[fast_choice]))
        eu_errors.append(float(np.max(np.abs(fast_utilities - reference_utilities))))
    if args.profile:
        print_profile(states_seen, weights, args.profile)
    fast_p50, reference_p50 = np.percentile(fast_ms, 50), np.percentile(reference_ms, 50)
    return {
        "scene_objects": n_objects, "n_train": n_train,
        "fast_ms": {"p50": round(float(fast_p50), 2), "p95": round(float(np.percentile(fast_ms, 95)), 2)},
        "fast_cpu_ms": {"p50": round(float(np.percentile(fast_cpu_ms, 50)), 2),
                        "p95": round(float(np.percentile(fast_cpu_ms, 95)), 2)},
        "reference_ms": {"p50": round(float(reference_p50), 1),
                         "p95": round(float(np.percentile(reference_ms, 95)), 1)},
        "reference_cpu_ms": {"p50": round(float(np.percentile(reference_cpu_ms, 50)), 1),
                             "p95": round(float(np.percentile(reference_cpu_ms, 95)), 1)},
        "speedup": round(float(reference_p50 / fast_p50), 1),
        "speedup_cpu": round(float(np.percentile(reference_cpu_ms, 50) / np.percentile(fast_cpu_ms, 50)), 1),
        "same_action": round(float(np.mean(same)), 4),
        "max_regret": float(f"{max(regrets):.3g}"),
        "max_eu_error": float(f"{max(eu_errors):.3g}"),
        "fast_cpu_ms_fsq_closed": _percentiles(by_fsq[False]), "fast_cpu_ms_fsq_open": _percentiles(by_fsq[True]),
        "es_cpu_ms": _percentiles(es_cpu_ms),
        "lapack_cpu_ms_fsq_closed": _percentiles(lapack_ms[False]),
        "lapack_cpu_ms_fsq_open": _percentiles(lapack_ms[True]),
        "states": args.states, "reference_states": with_reference, "feature_query_open": len(by_fsq[True]),
        "load_average": round(os.getloadavg()[0], 2),
    }


def _best_cpu_seconds(run, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        started = time.process_time()
        run()
        best = min(best, time.process_time() - started)
    return best


def _percentiles(values: list[float]) -> dict | None:
    """p50 and p95 in ms, or None when no state fell in the group."""
    if not values:
        return None
    return {"p50": round(float(np.percentile(values, 50)), 2), "p95": round(float(np.percentile(values, 95)), 2)}


def _split_line(row: dict) -> str:
    """Two lines: the CPU time by whether the feature query is open, with ES alone, then the part inside LAPACK."""
    def groups(pairs) -> str:
        return "; ".join(f"{label} " + ("-" if row[key] is None else
                                       f"p50 {row[key]['p50']:.2f} p95 {row[key]['p95']:.2f} ms")
                         for label, key in pairs)
    by_state = groups((("FSQ closed", "fast_cpu_ms_fsq_closed"), ("FSQ open", "fast_cpu_ms_fsq_open"),
                       ("ES alone", "es_cpu_ms")))
    inside = groups((("FSQ closed", "lapack_cpu_ms_fsq_closed"), ("FSQ open", "lapack_cpu_ms_fsq_open")))
    return f"           cpu by state: {by_state}\n           inside LAPACK: {inside}"


def main(args) -> int:
    weights = resolve_weights(args.weights)
    results = []
    print(f"DT decision, weights {args.weights}, |Y| = 4, |F| = 90, BLAS threads {args.threads}, "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    print(f"{'|X|':>4} {'n':>4} | {'fast p50':>9} {'p95':>7} | {'cpu p50':>8} {'p95':>7} | {'ref p50':>9} {'p95':>9} | "
          f"{'speedup':>8} {'cpu':>6} | {'same':>5} {'max regret':>10} {'max EU err':>10} | states (ref) | load")
    for n_train in args.train:
        for n_objects in args.objects:
            row = measure_size(n_objects, n_train, args, weights)
            results.append(row)
            print(f"{n_objects:>4} {n_train:>4} | {row['fast_ms']['p50']:>7.2f}ms {row['fast_ms']['p95']:>5.1f}ms | "
                  f"{row['fast_cpu_ms']['p50']:>6.2f}ms {row['fast_cpu_ms']['p95']:>5.1f}ms | "
                  f"{row['reference_ms']['p50']:>7.0f}ms {row['reference_ms']['p95']:>7.0f}ms | "
                  f"{row['speedup']:>7.0f}x {row['speedup_cpu']:>5.0f}x | {row['same_action']:>5.2f} "
                  f"{row['max_regret']:>10.2g} "
                  f"{row['max_eu_error']:>10.2g} | {row['states']} ({row['reference_states']}) | "
                  f"{row['load_average']:.1f}", flush=True)
            print(_split_line(row), flush=True)
    if args.json:
        print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main(ARGS))
