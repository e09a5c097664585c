"""``teachbot regress``: run a suite of scripted-teacher episodes, report, and compare with a baseline."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from dialog.commands._arguments import budget, positive_int
from dialog.experiments.analysis import evaluate_findings, summarise
from dialog.experiments.baseline import baseline_path, check_against_baseline, write_baseline
from dialog.experiments.features.report import feature_summaries, run_feature_suite, write_feature_report
from dialog.experiments.pools import load_pools
from dialog.experiments.recipes.report import write_recipe_report
from dialog.experiments.recipes.suite import (
    evaluate_recipe_findings,
    load_study,
    run_recipe_suite,
    summarise_study,
    trial_count,
)
from dialog.experiments.report import markdown_report, plot_learning_curves, plot_question_timing, write_episode_csvs
from dialog.experiments.runner import episode_specs, run_locally, run_on_ray
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
    suite = load_suite(args.suite, known_strategies=STRATEGY_NAMES).with_overrides(
        strategies=args.strategies, seeds=args.seeds, budget=args.budget, datasets=args.datasets)
    if suite.kind == "episodes":
        unknown = [s for s in suite.strategies if s not in STRATEGY_NAMES]
        if unknown:
            raise ValueError(f"unknown strategies {unknown}; choose from: {', '.join(STRATEGY_NAMES)}")
    out = args.results or Path("results") / suite.name
    check_writable(out, "results", folder=True)
    with writing(out, "results", inside=True):
        out.mkdir(parents=True, exist_ok=True)
        return _run_suite(args, suite, out)


def _run_suite(args: argparse.Namespace, suite, out: Path) -> int:
    started = time.perf_counter()
    if suite.kind == "feature-selection":
        rows = run_feature_suite(suite, load_pools(suite.task, suite.kitchen, 1, suite.plan_options))
        seconds = time.perf_counter() - started
        summaries = feature_summaries(rows, suite)
        findings = evaluate_findings(summaries, suite)
        report = write_feature_report(suite, rows, summaries, findings, seconds, out)
        count = len(rows)
    elif suite.kind == "episodes":
        load_pools(suite.task, suite.kitchen, suite.datasets, suite.plan_options)  # render once, before workers
        specs = episode_specs(suite, out)
        progress = not args.no_progress
        results = run_on_ray(specs, args.ray, progress) if args.ray else run_locally(specs, args.workers, progress)
        seconds = time.perf_counter() - started
        summaries = summarise(results, suite)
        findings = evaluate_findings(summaries, suite)
        write_episode_csvs(results, out)
        figures = plot_learning_curves(results, suite, out) + plot_question_timing(results, suite, out)
        report = markdown_report(suite, results, summaries, findings, seconds, out, figures)
        count = len(results)
    elif suite.kind == "recipes":
        study = load_study(suite)
        results = run_recipe_suite(study, args.workers, not args.no_progress)
        seconds = time.perf_counter() - started
        summaries = summarise_study(results, study)
        findings = evaluate_recipe_findings(summaries, suite)
        count = trial_count(results)
        report = write_recipe_report(suite, study, results, summaries, findings, seconds, out, count)
    else:
        raise ValueError(f"suite '{suite.name}' is of kind '{suite.kind}', which this version cannot run yet")
    print(f"{suite.name}: {count} runs in {seconds:.1f} s; report {report}")
    for outcome in findings:
        ps = ", ".join(f"{c.b} p={c.p:.3g}" for c in outcome.comparisons)
        print(f"  {outcome.finding.id}: {'holds' if outcome.holds else 'does not hold'} ({ps})")
    if args.update_baseline:
        with writing(baseline_path(suite), "baseline"):
            print(f"baseline written to {write_baseline(suite, summaries)}")
    failures = check_against_baseline(suite, summaries) if args.check else []
    for failure in failures:
        print(f"  REGRESSION {failure}")
    if args.json:
        print(json.dumps({"suite": suite.name, "episodes": count, "seconds": round(seconds, 2),
                          "passed": not failures, "failures": failures}))
    return 1 if failures else 0
