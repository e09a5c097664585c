"""How long DT's decisions take in the states a suite's episodes really reach, against the reference.

``bench_decision.py`` times seeded synthetic states at fixed sizes (|X| 55 with n 150 or 500 examples, the
feature query open in half of them). This script plays a suite's own episodes instead (the real dialog
manager, scripted teacher and data sets, as ``teachbot regress`` does) and times every decision the strategy
makes there, as the teacher would wait for it: CPU time of ``strategy.choose``, one BLAS thread, with the
engine's caches as the loop leaves them (a decision after a quiet turn reuses the what-ifs of the same model
version and scene; one after an answer is cold). Each decision is labelled with its training-set size,
scene size and whether the feature query is still open.

Every ``--reference-every``-th decision with a real choice (more than no query affordable) is also scored
by the brute-force reference engine, outside the timed section (the reference caches nothing and draws no
random number, so the episode is unchanged): the same action as the fast engine, the reference's regret of
the fast choice, and the speedup of the median fast decision over the median reference one in this run.

    python scripts/bench_played.py --suite ch6-static --condition static --json   # last line: one JSON object
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from dialog.experiments.episodes import run_episode
from dialog.experiments.runner import episode_specs
from dialog.experiments.suite import load_suite
from learning.decision.candidates import expected_decision_features
from learning.decision.weights import weighs_habits
from learning.errors import TeachbotError
from learning.strategies import DecisionTheoreticStrategy, make_strategy
from learning.strategies.decision_theoretic import choose_index


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="ch6-static", help="suite name or .toml path (default ch6-static)")
    parser.add_argument("--condition", nargs="+", help="only these conditions (default: every one)")
    parser.add_argument("--strategy", default="dt-task", help="a DT strategy of any form (default dt-task)")
    parser.add_argument("--datasets", type=int, default=2, help="training data sets (default 2)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0], help="episode seeds (default 0)")
    parser.add_argument("--budget", type=float, help="override every condition's question budget")
    parser.add_argument("--turns", type=int, help="override every condition's number of turns")
    parser.add_argument("--reference-every", type=int, default=10,
                        help="score every Nth decision with a choice by the reference too (default 10; 0: never)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if args.datasets < 1 or args.reference_every < 0 or (args.turns is not None and args.turns < 1) \
            or (args.budget is not None and args.budget < 0):
        parser.error("--datasets and --turns must be at least 1, --reference-every and --budget at least 0")
    return args


class DecisionLog:
    """Wraps one strategy's ``choose``: the CPU time of each call, with what the state looked like."""

    def __init__(self, strategy: DecisionTheoreticStrategy, reference_every: int):
        self.strategy, self.reference_every = strategy, reference_every
        self.rows: list[dict] = []
        self.checks: list[dict] = []
        self._choose, self._last_version, self._choices = strategy.choose, None, 0
        strategy.choose = self.choose  # type: ignore[method-assign]

    def choose(self, state, rng):
        cold = state.version != self._last_version
        started = time.process_time()
        decision = self._choose(state, rng)
        cpu_ms = 1e3 * (time.process_time() - started)
        self._last_version = state.version
        self.rows.append({"cpu_ms": cpu_ms, "n_train": len(state.examples), "scene": len(state.scene_X),
                          "fsq_open": not state.feature_query_asked, "cold": cold,
                          "candidates": 0 if self.strategy.last_candidates is None
                          else len(self.strategy.last_candidates.actions)})
        if self.rows[-1]["candidates"] > 1:  # a real choice (no query is not the only candidate)
            self._choices += 1
            if self.reference_every and self._choices % self.reference_every == 0:
                self.checks.append(self._check(state, cpu_ms))
        return decision

    def _check(self, state, fast_cpu_ms: float) -> dict:
        """The reference's choice on this state and its regret of the fast one (eq. 7.1), untimed by the episode."""
        strategy, fast = self.strategy, self.strategy.last_candidates  # what the timed choice saw
        habits = weighs_habits(strategy.weights)
        started = time.process_time()
        reference = expected_decision_features(state, "reference", strategy.window_factor,
                                               seconds=strategy.embodied, habits=habits)
        reference_cpu_ms = 1e3 * (time.process_time() - started)
        assert reference.actions == fast.actions, "both engines score the same candidates"
        fast_eu, reference_eu = fast.utilities(strategy.weights), reference.utilities(strategy.weights)
        fast_choice = choose_index(fast_eu, fast.seconds)
        reference_choice = choose_index(reference_eu, reference.seconds)
        return {"same": fast_choice == reference_choice,
                "regret": float(reference_eu[reference_choice] - reference_eu[fast_choice]),
                "fast_cpu_ms": fast_cpu_ms, "reference_cpu_ms": reference_cpu_ms}


def play(spec, strategy_name: str, reference_every: int) -> tuple[list, list]:
    """One episode with a fresh strategy: its decisions' rows and reference checks."""
    strategy = make_strategy(strategy_name)
    if not isinstance(strategy, DecisionTheoreticStrategy):
        sys.exit(f"bench_played: {strategy_name} is not a decision-theoretic strategy; this benchmark times DT's "
                 "what-if decisions (e.g. dt-task, dt-task-env, dt)")
    log = DecisionLog(strategy, reference_every)
    run_episode(spec, strategy)
    return log.rows, log.checks


def percentiles(values) -> dict | None:
    """p50, p95 and max in ms, or None for no decision."""
    if len(values) == 0:
        return None
    values = np.asarray(values, dtype=float)
    return {"p50": round(float(np.percentile(values, 50)), 2), "p95": round(float(np.percentile(values, 95)), 2),
            "max": round(float(values.max()), 2), "count": int(len(values))}


def summarise(condition: str, rows: list[dict], checks: list[dict]) -> dict:
    """One condition's decision times: all, after an answer (cold), with the feature query open, and the checks."""
    cpu = np.array([row["cpu_ms"] for row in rows])
    cold = np.array([row["cold"] for row in rows], dtype=bool)
    fsq = np.array([row["fsq_open"] for row in rows], dtype=bool)
    n_train = [row["n_train"] for row in rows]
    fast_check = np.median([c["fast_cpu_ms"] for c in checks]) if checks else None
    reference_check = np.median([c["reference_cpu_ms"] for c in checks]) if checks else None
    return {
        "condition": condition, "decisions": len(rows), "scene_objects": sorted({row["scene"] for row in rows}),
        "choices": int(sum(row["candidates"] > 1 for row in rows)),  # decisions with a question to choose
        "n_train": {"min": int(min(n_train)), "p50": int(np.median(n_train)), "max": int(max(n_train))},
        "fsq_open_share": round(float(fsq.mean()), 3),
        "cpu_ms": percentiles(cpu), "cpu_ms_cold": percentiles(cpu[cold]),
        "cpu_ms_fsq_open": percentiles(cpu[fsq]), "cpu_ms_fsq_closed": percentiles(cpu[~fsq]),
        "reference_checks": len(checks),
        "same_action": round(float(np.mean([c["same"] for c in checks])), 4) if checks else None,
        "max_regret": float(f"{max(c['regret'] for c in checks):.3g}") if checks else None,
        "reference_cpu_ms_p50": None if reference_check is None else round(float(reference_check), 1),
        "speedup_cpu": None if not checks else round(float(reference_check / max(fast_check, 1e-6)), 1),
    }


def _fmt(group: dict | None) -> str:
    return "-" if group is None else f"p50 {group['p50']:.1f} p95 {group['p95']:.1f} ms ({group['count']})"


def main(args) -> int:
    suite = load_suite(args.suite)
    conditions = [replace(c, budget=c.budget if args.budget is None else args.budget,
                          turns=c.turns if args.turns is None else args.turns)
                  for c in suite.conditions if not args.condition or c.name in args.condition]
    if not conditions:
        sys.exit(f"bench_played: --condition {' '.join(args.condition)} names no condition of suite {suite.name}; "
                 f"accepted: {', '.join(c.name for c in suite.conditions)}")
    suite = replace(suite, strategies=(args.strategy,), datasets=args.datasets, seeds=tuple(args.seeds),
                    conditions=tuple(conditions))
    overrides = "".join(f", {name} {value:g} in every condition" for name, value in
                        (("budget", args.budget), ("turns", args.turns)) if value is not None)
    print(f"DT decisions as played: suite {suite.name}{overrides}, strategy {args.strategy}, "
          f"{args.datasets} data sets, seeds {args.seeds}, one BLAS thread, CPU time, "
          f"load average {os.getloadavg()[0]:.2f}", flush=True)
    summaries = []
    with tempfile.TemporaryDirectory() as results:
        specs = episode_specs(suite, Path(results))
        warm_up = [row["cpu_ms"] for row in play(specs[0], args.strategy, 0)[0]]
        print(f"warm-up (the first episode, played once untimed): its slowest decision {max(warm_up):.1f} ms, with "
              "the process's one-time costs (e.g. Python's first full garbage collection after the data sets load)",
              flush=True)
        for condition in conditions:
            rows, checks = [], []
            for spec in (s for s in specs if s.condition.name == condition.name):
                played, checked = play(spec, args.strategy, args.reference_every)
                rows += played
                checks += checked
            row = summarise(condition.name, rows, checks)
            summaries.append(row)
            print(f"{condition.name}: {row['decisions']} decisions, |X| {row['scene_objects']}, n_train "
                  f"{row['n_train']['min']}-{row['n_train']['max']} (median {row['n_train']['p50']}), feature query "
                  f"open in {row['fsq_open_share']:.0%}\n  all {_fmt(row['cpu_ms'])}; after an answer "
                  f"{_fmt(row['cpu_ms_cold'])}\n  feature query open {_fmt(row['cpu_ms_fsq_open'])}; closed "
                  f"{_fmt(row['cpu_ms_fsq_closed'])}\n  reference on {row['reference_checks']} of them: "
                  f"p50 {row['reference_cpu_ms_p50']} ms, speedup {row['speedup_cpu']}x, same action "
                  f"{row['same_action']}, max regret {row['max_regret']}", flush=True)
    if args.json:
        print(json.dumps({"suite": suite.name, "budget": args.budget, "turns": args.turns,
                          "strategy": args.strategy, "datasets": args.datasets,
                          "seeds": list(args.seeds), "load_average": round(os.getloadavg()[0], 2),
                          "conditions": summaries}))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(_parse(sys.argv[1:])))
    except TeachbotError as error:  # a suite, strategy or setting we cannot run: one line, no traceback
        sys.exit(f"bench_played: {error}")
