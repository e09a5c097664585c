"""``teachbot regress``: run a suite of scripted-teacher episodes, report, and compare with a baseline.

The command parses its arguments and prints; the suite's kind (``dialog/experiments/kinds.py``)
does the work: load, run, report, check.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from dialog.commands._arguments import budget, positive_int
from dialog.experiments.baseline import baseline_path, write_baseline
from dialog.experiments.kinds import RunOptions, get_kind, run_suite
from dialog.experiments.suite import load_suite, suite_names
from dialog.output_paths import check_writable, writing
from learning.strategies import STRATEGY_NAMES


def register(commands) -> None:
    parser = commands.add_parser("regress", help="run a regression suite with scripted teachers")
    parser.add_argument("--suite", required=True, help=f"suite name ({', '.join(suite_names())}) or a .toml path")
    parser.add_argument("--results", type=Path, default=None, help="results folder (default results/<suite>)")
    parser.add_argument("--strategies", nargs="+", default=None, help="run only these strategies")
    parser.add_argument("--seeds", nargs="+", type=int, default=None, help="override the suite's seeds")
    parser.add_argument("--budget", type=budget, default=None, help="override every condition's budget")
    parser.add_argument("--datasets", type=positive_int, default=None, help="override the number of data sets")
    parser.add_argument("--workers", type=positive_int, default=None, help="local worker processes (default: cores)")
    parser.add_argument("--ray", metavar="ADDRESS", default=None,
                        help="run the episodes on the Ray cluster at ADDRESS ('local' starts one here)")
    parser.add_argument("--check", action="store_true", help="exit 1 when a strategy leaves its baseline band")
    parser.add_argument("--update-baseline", action="store_true", help="store this run as the suite's baseline")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the run")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    original = load_suite(args.suite, known_strategies=STRATEGY_NAMES)
    kind = get_kind(original.kind)
    suite = kind.load(original.with_overrides(strategies=args.strategies, seeds=args.seeds, budget=args.budget,
                                              datasets=args.datasets))
    out = args.results or Path("results") / suite.name
    check_writable(out, "results", folder=True)
    with writing(out, "results", inside=True):
        out.mkdir(parents=True, exist_ok=True)
        options = RunOptions(results=out, workers=args.workers, ray=args.ray, progress=not args.no_progress)
        outcome = run_suite(kind, suite, options, original)
        report = kind.report(outcome, out)[0]
    print(f"{suite.name}: {outcome.count} runs in {outcome.seconds:.1f} s; report {report}")
    for finding in outcome.findings:
        ps = ", ".join(f"{c.b} p={c.p:.3g}" for c in finding.comparisons)
        print(f"  {finding.finding.id}: {finding.verdict}" + (f" ({ps})" if ps else ""))
    if args.update_baseline:
        with writing(baseline_path(suite), "baseline"):
            print(f"baseline written to {write_baseline(suite, outcome.summaries)}")
    failures = kind.check(outcome) if args.check else []
    for failure in failures:
        print(f"  REGRESSION {failure}")
    if args.json:
        print(json.dumps({"suite": suite.name, "episodes": outcome.count, "seconds": round(outcome.seconds, 2),
                          "passed": not failures, "failures": failures}))
    return 1 if failures else 0
