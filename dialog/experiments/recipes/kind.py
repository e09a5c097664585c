"""The recipes kind: the chapter-4 experiments (arms x recipes x demonstrations m) in parallel."""

from __future__ import annotations

import time
from pathlib import Path

from dialog.experiments.kinds import RunOptions, SuiteKind, SuiteRun
from dialog.experiments.recipes.report import write_recipe_report
from dialog.experiments.recipes.suite import (
    evaluate_recipe_findings,
    load_study,
    run_recipe_suite,
    summarise_study,
    trial_count,
)
from dialog.experiments.registry import register_kind
from dialog.experiments.suite import Suite


@register_kind
class RecipesKind(SuiteKind):
    name = "recipes"

    def load(self, suite: Suite) -> Suite:
        load_study(suite)  # every option, arm and finding checked before anything runs
        return suite

    def run(self, suite: Suite, options: RunOptions) -> SuiteRun:
        started = time.perf_counter()
        study = load_study(suite)
        results = run_recipe_suite(study, options.workers, options.progress)
        summaries = summarise_study(results, study)
        return SuiteRun(suite, results, summaries, evaluate_recipe_findings(summaries, suite), trial_count(results),
                        time.perf_counter() - started, extra={"study": study})

    def report(self, run: SuiteRun, folder: Path) -> list[Path]:
        report = write_recipe_report(run.suite, run.extra["study"], run.data, run.summaries, run.findings,
                                     run.seconds, folder, run.count)
        return [report, folder / "runs.csv", folder / "execution.csv"]
