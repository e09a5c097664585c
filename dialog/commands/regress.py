"""``teachbot regress``: run a suite of scripted-teacher episodes, report, and compare with a baseline.

The command parses its arguments and prints; the suite's kind (``dialog/experiments/kinds.py``)
does the work: load, run, report, check.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from dialog.commands._arguments import budget, data_seed, positive_int, seeds
from dialog.commands._json import print_json
from dialog.experiments.baseline import (
    baseline_path,
    refuse_baseline_from_another_run,
    refuse_other_data_seed,
    write_baseline,
)
from dialog.experiments.kinds import RunOptions, get_kind, run_suite
from dialog.experiments.progress import EventProgress, Progress, SweepProgress
from dialog.experiments.runner import EpisodePool, episode_specs
from dialog.experiments.suite import load_suite, suite_names
from dialog.output_paths import check_writable, writing
from dialog.printed_command import command_line
from dialog.user_weights import named_weights, read_named_weights
from learning.datafiles import inside
from learning.errors import SettingsError
from learning.limits import check_limit
from learning.strategies import STRATEGY_NAMES


def register(commands) -> None:
    parser = commands.add_parser(
        "regress", help="run a regression suite with scripted teachers",
        description="Run every episode of a suite (strategies x conditions x seeds) with scripted teachers, write "
                    "learning curves, tables with significance tests and plots to the results folder, and compare "
                    "with the stored baseline (--check exits 1 on a regression).")
    parser.add_argument("--suite", required=True, help=f"suite name ({', '.join(suite_names())}) or a .toml path")
    parser.add_argument("--results", type=Path, default=None, help="results folder (default results/<suite>)")
    parser.add_argument("--strategies", nargs="+", default=None,
                        help="run only these strategies; rl:FILE adds a trained questioner policy "
                             "(teachbot train-questioner), module.path:ClassName your own Strategy class from an "
                             "importable module (this runs your code)")
    parser.add_argument("--seeds", nargs="+", type=seeds, default=None, help="override the suite's seeds")
    parser.add_argument("--budget", type=budget, default=None, help="override every condition's budget")
    parser.add_argument("--datasets", type=positive_int, default=None, help="override the number of data sets")
    parser.add_argument("--data-seed", type=data_seed, default=None, metavar="N",
                        help="render (once, then cached) and use the task's data sets from seed N instead of the "
                             "suite's (default: the suite's data_seed, 0 unless it says otherwise)")
    parser.add_argument("--data-seeds", type=data_seed, nargs="+", default=None, metavar="N",
                        help="run the suite on the data sets of each of these data seeds (each report in "
                             "<results>/data-seed-N/) and test its findings per data seed and pooled over all "
                             "(<results>/replication.md)")
    parser.add_argument("--weights", type=named_weights, action="append", default=None, metavar="NAME=FILE",
                        help="add a DT strategy called NAME with the weights in FILE (as teachbot learn-weights "
                             "writes them); repeatable")
    parser.add_argument("--embodied-costs", action="store_true",
                        help="every condition with embodied costs (a turn lasts what it takes; DT weighs questions by "
                             "their expected seconds); a condition without 'seconds' gets the default allocation of "
                             "dialog/data/embodied-costs.toml")
    parser.add_argument("--workers", type=positive_int, default=None, help="local worker processes (default: cores)")
    parser.add_argument("--ray", metavar="ADDRESS", default=None,
                        help="run the episodes on the Ray cluster at ADDRESS ('local' starts one here)")
    parser.add_argument("--check", action="store_true", help="exit 1 when a strategy leaves its baseline band")
    parser.add_argument("--update-baseline", action="store_true", help="store this run as the suite's baseline")
    parser.add_argument("--no-progress", action="store_true", help="no progress line")
    parser.add_argument("--progress-events", action="store_true",
                        help="instead of the progress line, one line per finished episode on standard error, "
                             "for a parent process that shows the progress of a longer run (make experiments)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the run")
    parser.add_argument("--render-only", action="store_true",
                        help="render (or find in the cache) the data sets the run would use, for each data seed, "
                             "and stop: no episode is played and nothing is written to the results folder")
    parser.set_defaults(handler=run)


def _embodied_seconds(args: argparse.Namespace) -> float | None:
    if not args.embodied_costs:
        return None
    from dialog.embodied import default_allocation

    return default_allocation()


def shows_bars(args: argparse.Namespace) -> bool:
    """Bars and lines of the run's own (not with --no-progress, nor for a parent process reading events)."""
    return not (args.no_progress or args.progress_events)


@contextmanager
def sweep_progress(args: argparse.Namespace, kind, suite, out: Path, data_seeds: int) -> Iterator[Progress | None]:
    """The one progress line of the whole run (every episode of every data seed), or the events a parent reads;
    None where the kind shows its own (not an episodes suite) or nothing is shown (--no-progress)."""
    if args.progress_events:
        yield EventProgress()
        return
    if args.no_progress or kind.name != "episodes":
        yield None
        return
    line = SweepProgress(len(episode_specs(suite, out)) * data_seeds)
    try:
        yield line
    finally:
        line.close()


def run(args: argparse.Namespace) -> int:
    if args.workers is not None:
        check_limit("workers", args.workers, "--workers")  # before the suite's data sets are loaded
    original = load_suite(args.suite, known_strategies=STRATEGY_NAMES).with_weights(read_named_weights(args.weights))
    kind = get_kind(original.kind)
    suite = kind.load(original.with_overrides(strategies=args.strategies, seeds=args.seeds, budget=args.budget,
                                              datasets=args.datasets, data_seed=args.data_seed,
                                              embodied_seconds=_embodied_seconds(args)))
    if args.render_only:
        return render_only(args, kind, suite)
    if args.update_baseline:
        refuse_baseline_from_another_run(suite, original)  # before anything runs
    if args.check:
        refuse_other_data_seed(suite)  # before anything runs
        if args.embodied_costs:
            raise SettingsError("--check compares with the stored baseline, which was made in turns; run "
                                "--embodied-costs without --check")
    out = args.results or inside(Path("results"), Path("results") / suite.name, "results folder")
    check_writable(out, "results", folder=True)
    if suite.kitchens:
        return run_across_kitchens(args, kind, suite, original, out)
    if args.data_seeds is not None:
        return run_on_data_seeds(args, kind, suite, original, out)
    with writing(out, "results", inside=True), sweep_progress(args, kind, suite, out, 1) as sweep:
        out.mkdir(parents=True, exist_ok=True)
        options = RunOptions(results=out, workers=args.workers, ray=args.ray, progress=shows_bars(args), sweep=sweep)
        outcome = run_suite(kind, suite, options, original)
        report = kind.report(outcome, out)[0]
    print(f"{suite.name}: {outcome.count} runs in {outcome.seconds:.1f} s; report {report}")
    sweep = outcome.extra.get("sweep")
    if sweep is not None:
        print(f"  {sweep.line()}")
    for finding in outcome.findings:
        ps = ", ".join(f"{c.b} p={c.p:.3g}" + ("" if c.p_holm is None else f" (Holm {c.p_holm:.3g})")
                       for c in finding.comparisons)
        print(f"  {finding.finding.id}: {finding.verdict}" + (f" ({ps})" if ps else ""))
    if args.update_baseline:
        with writing(baseline_path(suite), "baseline"):
            print(f"baseline written to {write_baseline(suite, outcome.summaries)}")
    failures = kind.check(outcome) if args.check else []
    if args.check and suite.weights:
        print(f"  not checked (--weights strategies, no baseline): {', '.join(suite.weights)}")
    for failure in failures:
        print(f"  REGRESSION {failure}")
    if args.check:
        print(failures.verdict())
    if args.json:
        data = {} if suite.kind == "recipes" else {"data_seed": suite.data_seed}  # recipes render no data sets
        use = {} if sweep is None else {"episodes_per_second": round(sweep.runs_per_second, 3),
                                        "cpu_use": round(sweep.cpu_use, 3)}
        print_json({"suite": suite.name, "episodes": outcome.count, "seconds": round(outcome.seconds, 2),
                          **data, **use, "passed": not failures, "failures": failures})
    return 1 if failures else 0


def render_only(args: argparse.Namespace, kind, suite) -> int:
    """--render-only: the data sets of every data seed the run would use, rendered once (then cached), before a
    long run; plays no episode, so it reads no result."""
    import time

    from dialog.experiments.pools import load_pools
    from dialog.experiments.runner import RenderBar

    for refused in ("check", "update_baseline"):
        if getattr(args, refused):
            raise SettingsError(f"--render-only plays no episode; --{refused.replace('_', '-')} needs a run: give "
                                "one or the other")
    if kind.name != "episodes":
        raise SettingsError(f"--render-only renders the data sets of episodes suites; '{suite.name}' is a "
                            f"{kind.name} suite")
    data_seeds = list(dict.fromkeys(args.data_seeds or [suite.data_seed]))
    for seed in data_seeds:
        started, what = time.perf_counter(), f"{suite.task}/{suite.kitchen} (data seed {seed})"
        with RenderBar(what, shows_bars(args)) as bar:
            load_pools(suite.task, suite.kitchen, suite.datasets, suite.plan_options, progress=bar, data_seed=seed)
        print(f"{suite.name}: the data sets of {what} are ready ({time.perf_counter() - started:.0f} s)", flush=True)
    if args.json:
        print_json({"suite": suite.name, "data_seeds": data_seeds, "rendered": True})
    return 0


@contextmanager
def shared_pool(args: argparse.Namespace) -> Iterator:
    """One pool of worker processes for every data seed of the run (``EpisodePool``), or None where each run
    has its own way (Ray, or one worker: episodes in this process)."""
    workers = args.workers or os.cpu_count() or 1
    if args.ray or workers < 2:
        yield None
        return
    with EpisodePool(workers) as pool:
        yield pool


def run_across_kitchens(args: argparse.Namespace, kind, suite, original, out: Path) -> int:
    """A suite that names ``kitchens``: one run in each (``<out>/kitchen-NAME/``, on every --data-seeds seed
    too), then the strategies' ranks per kitchen and Kendall's W across them (``kitchens.md``)."""
    from dataclasses import replace

    import numpy as np

    from dialog.experiments.kitchens import label, pooled_means, rank_agreement, read_replication, write_rankings

    for refused in ("check", "update_baseline"):
        if getattr(args, refused):
            raise SettingsError(f"suite '{suite.name}' runs in {len(suite.kitchens)} kitchens; "
                                f"--{refused.replace('_', '-')} compares or stores one run: run one kitchen's suite")
    means: dict[str, dict[str, dict[str, float]]] = {}  # condition -> kitchen -> strategy -> mean
    for kitchen in suite.kitchens:
        here, folder = replace(suite, kitchen=kitchen, kitchens=()), out / f"kitchen-{label(kitchen)}"
        print(f"{suite.name} in {label(kitchen)}", flush=True)
        if args.data_seeds is not None:
            run_on_data_seeds(args, kind, here, original, folder)
            for condition, by_strategy in pooled_means(read_replication(folder)).items():
                means.setdefault(condition, {})[kitchen] = by_strategy
            continue
        with writing(folder, "results", inside=True):
            folder.mkdir(parents=True, exist_ok=True)
            outcome = run_suite(kind, here, RunOptions(results=folder, workers=args.workers, ray=args.ray,
                                                       progress=shows_bars(args)), original)
            kind.report(outcome, folder)
        for summary in outcome.summaries:
            means.setdefault(summary.condition, {}).setdefault(kitchen, {})[summary.strategy] = float(summary.mean[-1])
    rng = np.random.default_rng(0)
    rankings = {condition: rank_agreement(by_kitchen, suite.strategies, rng) for condition, by_kitchen in means.items()}
    words = ["regress", "--suite", args.suite] + (["--data-seeds", *args.data_seeds] if args.data_seeds else [])
    with writing(out, "results", inside=True):
        path = write_rankings(suite.name, rankings, out, command_line(words))
    print(f"across {len(suite.kitchens)} kitchens: {path}")
    for condition, result in rankings.items():
        if "w" in result:
            print(f"  {condition}: Kendall's W {result['w']:.3f} [{result['ci'][0]:.3f}, {result['ci'][1]:.3f}]")
    if args.json:
        print_json({"suite": suite.name, "kitchens": [label(k) for k in suite.kitchens],
                    "kendalls_w": {c: r.get("w") for c, r in rankings.items()}})
    return 0


def run_on_data_seeds(args: argparse.Namespace, kind, suite, original, out: Path) -> int:
    """--data-seeds: one run per data seed, each with its report, then the findings pooled over all of them."""
    from dialog.experiments.data_seeds import (
        pooled_findings,
        replication_report,
        replication_summary,
        write_replication_json,
    )

    seeds = list(dict.fromkeys(args.data_seeds))
    if len(seeds) != len(args.data_seeds):
        raise SettingsError(f"--data-seeds: each data seed once, got {' '.join(map(str, args.data_seeds))}")
    for refused in ("data_seed", "check", "update_baseline"):
        if getattr(args, refused) not in (None, False):
            raise SettingsError(f"--data-seeds runs several data sets; --{refused.replace('_', '-')} compares or "
                                "stores one: give one or the other")
    if kind.name != "episodes":
        raise SettingsError(f"--data-seeds renders the data sets of episodes suites; '{suite.name}' is a "
                            f"{kind.name} suite")
    runs = {}
    with sweep_progress(args, kind, suite, out, len(seeds)) as sweep, shared_pool(args) as pool:
        def options_for(seed: int) -> RunOptions:
            return RunOptions(results=out / f"data-seed-{seed}", workers=args.workers, ray=args.ray,
                              progress=shows_bars(args), sweep=sweep, pool=pool)

        for index, seed in enumerate(seeds):
            folder = out / f"data-seed-{seed}"
            if sweep is not None:
                sweep.describe(f"data seed {seed}")
            with writing(folder, "results", inside=True):
                folder.mkdir(parents=True, exist_ok=True)
                runs[seed] = run_suite(kind, suite.with_overrides(data_seed=seed), options_for(seed), original)
            if pool is not None and index + 1 < len(seeds):  # the next data seed's episodes run meanwhile
                following = seeds[index + 1]
                with writing(out / f"data-seed-{following}", "results", inside=True):
                    kind.start(suite.with_overrides(data_seed=following), options_for(following))
            with writing(folder, "results", inside=True):
                report = kind.report(runs[seed], folder)[0]
            done = (f"{suite.name} on data seed {seed}: {runs[seed].count} runs in {runs[seed].seconds:.1f} s; "
                    f"report {report}")
            if isinstance(sweep, SweepProgress):
                sweep.note(done)
            else:
                print(done, flush=True)
    pooled = pooled_findings(suite, runs)
    words = ["regress", "--suite", args.suite, "--data-seeds", *seeds]
    for option, values in (("--strategies", args.strategies), ("--seeds", args.seeds), ("--datasets", args.datasets)):
        if values is not None:
            words += [option, *(values if isinstance(values, list) else [values])]
    command = command_line(words)  # the report's record of the run, runnable as printed
    with writing(out, "results", inside=True):
        path = replication_report(suite, runs, pooled, out, command)
        write_replication_json(replication_summary(suite, runs, pooled, command), out)
    print(f"pooled over data seeds {', '.join(map(str, seeds))}: {path}")
    for outcome in pooled:
        print(f"  {outcome.finding.id}: {outcome.verdict}")
    if args.json:
        print_json({"suite": suite.name, "data_seeds": seeds, "episodes": sum(r.count for r in runs.values()),
                          "seconds": round(sum(r.seconds for r in runs.values()), 2),
                          "pooled": {o.finding.id: o.verdict for o in pooled}})
    return 0
