"""The episodes kind: every (condition, strategy, data set, seed) as one scripted-teacher episode (ch. 6, 7)."""

from __future__ import annotations

import os
import time
from pathlib import Path

from dialog.embodied import strategy_names_with_variants
from dialog.experiments.analysis import evaluate_findings, summarise
from dialog.experiments.figures import save_figures
from dialog.experiments.kinds import RunOptions, SuiteKind, SuiteRun, SweepUse
from dialog.experiments.pools import load_pools
from dialog.experiments.registry import register_kind
from dialog.experiments.report import markdown_report, write_episode_csvs
from dialog.experiments.runner import RenderBar, episode_specs, run_locally, run_on_ray
from dialog.experiments.suite import Suite, SuiteError
from learning.errors import SettingsError
from learning.strategies import STRATEGY_NAMES, check_strategy_name


@register_kind
class EpisodesKind(SuiteKind):
    name = "episodes"

    def load(self, suite: Suite) -> Suite:
        where = suite.path or suite.name
        known = strategy_names_with_variants(STRATEGY_NAMES)  # NAME+turns: DT blind to embodied costs
        for name in suite.strategies:  # a bad policy file or user class is one message now, not in every worker
            if name not in suite.weights:
                try:
                    check_strategy_name(name, known)
                except SettingsError as error:
                    raise SuiteError(f"{where}: {error}") from None
        for finding in suite.findings:
            if finding.at not in suite.checkpoints:
                raise SuiteError(f"{where}: finding '{finding.id}' compares at {finding.at}, which is not one of "
                                 f"the checkpoints {list(suite.checkpoints)}")
        return suite

    def start(self, suite: Suite, options: RunOptions) -> list:
        """Render the suite's data sets (once, before the workers) and, with a shared ``options.pool``, start its
        episodes there now; the specs of every episode."""
        what = f"{suite.task}/{suite.kitchen}" + (f" (data seed {suite.data_seed})" if suite.data_seed else "")
        with RenderBar(what, options.progress) as bar:
            load_pools(suite.task, suite.kitchen, suite.datasets, suite.plan_options, progress=bar,
                       data_seed=suite.data_seed)
        specs = episode_specs(suite, options.results)
        if options.pool is not None:
            options.pool.submit(specs)
        return specs

    def run(self, suite: Suite, options: RunOptions) -> SuiteRun:
        started = time.perf_counter()
        specs = self.start(suite, options)
        sweep_started = time.perf_counter()
        progress = options.progress if options.sweep is None else options.sweep
        if options.pool is not None:
            results = options.pool.results(specs, progress)
        elif options.ray:
            results = run_on_ray(specs, options.ray, progress)
        else:
            results = run_locally(specs, options.workers, progress)
        sweep = SweepUse(len(results), time.perf_counter() - sweep_started,
                         sum(r["cpu_seconds"] for r in results), os.cpu_count() or 1)
        summaries = summarise(results, suite)
        return SuiteRun(suite, results, summaries, evaluate_findings(summaries, suite), len(results),
                        time.perf_counter() - started, extra={"sweep": sweep})

    def report(self, run: SuiteRun, folder: Path) -> list[Path]:
        table = write_episode_csvs(run.data, folder)
        figures = save_figures(run.data, run.suite, folder)
        report = markdown_report(run.suite, run.data, run.summaries, run.findings, run.seconds, folder, figures)
        return [report, table, *figures]
