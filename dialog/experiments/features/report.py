"""Run and report a chapter-5 feature-selection suite (kind = "feature-selection")."""

from __future__ import annotations

import csv
from collections import defaultdict
from pathlib import Path

import numpy as np

from dialog.experiments.analysis import CheckpointSummary, FindingResult, pairwise
from dialog.experiments.features.study import METHODS, UserModel, run_study
from dialog.experiments.figures import pyplot
from dialog.experiments.report import _fmt_p, findings_closing_lines, write_markdown
from dialog.experiments.suite import Suite
from learning.errors import SettingsError
from learning.significance import mean_and_standard_error


def run_feature_suite(suite: Suite, pools) -> list[dict]:
    """The study over the suite's first training pool and the test pool."""
    train, test = pools.train, pools.test
    options = suite.options
    relevant = set(options.get("relevant_features", [])) or _task_relevant(suite)
    user = UserModel(**options.get("user_model", {}))
    methods = tuple(s for s in suite.strategies if s in METHODS)
    unknown = [s for s in suite.strategies if s not in METHODS]
    if unknown:
        raise SettingsError(f"suite '{suite.name}': unknown approaches {unknown}; accepted: {', '.join(METHODS)}")
    return run_study(train[0], test, relevant, sizes=suite.checkpoints, samples=int(options.get("samples", 10)),
                     users=int(options.get("users", 10)), user_model=user, seed=suite.seeds[0], methods=methods)


def _task_relevant(suite: Suite) -> set[str]:
    from bullet_world.catalogue import load_task
    from bullet_world.features import feature_catalogue

    task = load_task(suite.task)
    names = getattr(task, "relevant_features", None)
    if names:
        return set(names)
    return {info.name for info in feature_catalogue() if info.group.startswith(("object/appearance",
                                                                                 "object/geometry", "object/weight"))}


def feature_summaries(rows: list[dict], suite: Suite) -> list[CheckpointSummary]:
    """One summary per (n, approach): condition "n12", checkpoint n, the accuracies of every sample and user."""
    groups: dict = defaultdict(list)
    for row in rows:
        groups[(row["n"], row["method"])].append(row["accuracy"])
    summaries = []
    for (n, method), values in groups.items():
        column = np.array(values)[:, None]
        mean, error = mean_and_standard_error(column)
        summaries.append(CheckpointSummary(f"n{n}", method, (n,), mean, error, column))
    return summaries


def write_feature_report(suite: Suite, rows: list[dict], summaries: list[CheckpointSummary],
                         findings: list[FindingResult], seconds: float, out: Path) -> Path:
    plt = pyplot()
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "runs.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=["method", "n", "sample", "user", "accuracy", "features"])
        writer.writeheader()
        writer.writerows(rows)
    sizes = suite.checkpoints
    figure, axes = plt.subplots(1, len(sizes), figsize=(6 * len(sizes), 4), squeeze=False)
    lines = [f"# Regression report: {suite.name}", "", suite.description, "",
             f"- task `{suite.task}`, {len(rows)} trained classifiers in {seconds:.1f} s; "
             "raw rows: [runs.csv](runs.csv)", f"- data sets rendered from data seed {suite.data_seed}",
             "", "![accuracy by approach](accuracy.png)", ""]
    for axis, n in zip(axes[0], sizes):
        group = [s for s in summaries if s.condition == f"n{n}"]
        axis.bar([s.strategy for s in group], [s.mean[0] for s in group], yerr=[s.error[0] for s in group],
                 capsize=3, color="tab:blue")
        axis.set_title(f"n = {n} training instances")
        axis.set_ylabel("held-out accuracy (RBF SVM)")
        axis.tick_params(axis="x", rotation=45)
        axis.set_ylim(0, 1)
        lines += [f"## n = {n}", "", "| approach | accuracy | samples x users | mean features |", "|---|---|---|---|"]
        for s in group:
            used = np.mean([r["features"] for r in rows if r["n"] == n and r["method"] == s.strategy])
            lines.append(f"| {s.strategy} | {s.mean[0]:.3f} ± {s.error[0]:.3f} | {len(s.values)} | {used:.1f} |")
        lines += ["", "Two-sided Mann-Whitney U between approaches:", "", "| a | b | mean a | mean b | U | p |",
                  "|---|---|---|---|---|---|"]
        for c in pairwise(summaries, f"n{n}", 0):
            lines.append(f"| {c.a} | {c.b} | {c.mean_a:.3f} | {c.mean_b:.3f} | {c.u:.1f} | {_fmt_p(c.p)} |")
        lines.append("")
    figure.tight_layout()
    figure.savefig(out / "accuracy.png", dpi=110)
    plt.close(figure)
    if findings:
        lines += ["## The thesis's findings (table 5.6), tested here", "",
                  "| finding | comparison | mean | U | p (one-tailed) | holds? |", "|---|---|---|---|---|---|"]
        for outcome in findings:
            for c in outcome.comparisons:
                lines.append(f"| {outcome.finding.id}: {outcome.finding.text} | {c.a} > {c.b} | {c.mean_a:.3f} vs "
                             f"{c.mean_b:.3f} | {c.u:.1f} | {_fmt_p(c.p)} | {'yes' if c.significant else 'no'} |")
        lines += findings_closing_lines(findings, suite.analysis)
    return write_markdown(lines, out)
