"""The feature-selection kind: the chapter-5 study (approaches x training-set sizes n) on one training pool."""

from __future__ import annotations

import time
from pathlib import Path

from dialog.experiments.analysis import evaluate_findings
from dialog.experiments.features.report import feature_summaries, run_feature_suite, write_feature_report
from dialog.experiments.features.study import METHODS
from dialog.experiments.kinds import RunOptions, SuiteKind, SuiteRun
from dialog.experiments.pools import load_pools
from dialog.experiments.registry import register_kind
from dialog.experiments.runner import RenderBar
from dialog.experiments.suite import Suite, SuiteError


@register_kind
class FeatureSelectionKind(SuiteKind):
    name = "feature-selection"

    def load(self, suite: Suite) -> Suite:
        unknown = [s for s in suite.strategies if s not in METHODS]
        if unknown:
            raise SuiteError(f"{suite.path or suite.name}: unknown approaches {unknown} in 'strategies'; "
                             f"accepted: {', '.join(METHODS)}")
        return suite

    def run(self, suite: Suite, options: RunOptions) -> SuiteRun:
        started = time.perf_counter()
        with RenderBar(f"{suite.task}/{suite.kitchen}", options.progress) as bar:
            pools = load_pools(suite.task, suite.kitchen, 1, suite.plan_options, progress=bar,
                               data_seed=suite.data_seed)
        rows = run_feature_suite(suite, pools)
        summaries = feature_summaries(rows, suite)
        return SuiteRun(suite, rows, summaries, evaluate_findings(summaries, suite), len(rows),
                        time.perf_counter() - started)

    def report(self, run: SuiteRun, folder: Path) -> list[Path]:
        report = write_feature_report(run.suite, run.data, run.summaries, run.findings, run.seconds, folder)
        return [report, folder / "runs.csv", folder / "accuracy.png"]
