"""Write a suite's results: per-episode CSV, learning curves, question timing, tables, a Markdown report."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from dialog.experiments.analysis import CheckpointSummary, FindingResult, group_results, pairwise
from dialog.experiments.episodes import SERIES
from dialog.experiments.suite import Suite
from learning.significance import mean_and_standard_error


def write_episode_csvs(results: list[dict], out: Path) -> Path:
    """One CSV per episode (turn, accuracy, questions by type, budget) and one summary row per episode."""
    summary_path = out / "episodes.csv"
    out.mkdir(parents=True, exist_ok=True)
    with open(summary_path, "w", newline="") as summary_file:
        summary = csv.writer(summary_file)
        summary.writerow(["condition", "strategy", "dataset", "seed", "accuracy", "questions", "label", "demo",
                          "feature", "spent", "seconds", "csv"])
        for result in results:
            spec, series = result["spec"], result["series"]
            path = out / "episodes" / spec["condition"]["name"] / f"{spec['strategy']}-d{spec['dataset']}" \
                f"-s{spec['seed']}.csv"
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(path, "w", newline="") as handle:
                writer = csv.writer(handle)
                writer.writerow(SERIES)
                writer.writerows(zip(*(series[name] for name in SERIES)))
            summary.writerow([spec["condition"]["name"], spec["strategy"], spec["dataset"], spec["seed"],
                              f"{result['accuracy']:.4f}", series["questions"][-1], series["label"][-1],
                              series["demo"][-1], series["feature"][-1], series["spent"][-1],
                              f"{result['seconds']:.2f}", path.relative_to(out)])
    return summary_path


def _curves(group: list[dict], x_key: str, length: int) -> np.ndarray:
    """Accuracy indexed by questions asked (last value at each count) or by turn, padded with NaN."""
    curves = np.full((len(group), length), np.nan)
    for row, result in enumerate(group):
        series = result["series"]
        accuracy = np.asarray(series["accuracy"], dtype=float)
        if x_key == "turn":
            curves[row, :len(accuracy)] = accuracy[:length]
        else:
            for turn, asked in enumerate(series["questions"]):
                if asked < length:
                    curves[row, asked] = accuracy[turn]
    return curves


def plot_learning_curves(results: list[dict], suite: Suite, out: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    groups = group_results(results)
    for condition in suite.conditions:
        figure, axes = plt.subplots(1, 2, figsize=(12, 4.5))
        for strategy in suite.strategies:
            group = groups.get((condition.name, strategy), [])
            if not group:
                continue
            for axis, key, length in ((axes[0], "questions", int(max(r["series"]["questions"][-1] for r in group)) + 1),
                                      (axes[1], "turn", condition.turns)):
                mean, error = mean_and_standard_error(_curves(group, key, length))
                x = np.arange(length) if key == "questions" else np.arange(1, length + 1)
                line, = axis.plot(x, mean, label=strategy)
                axis.fill_between(x, mean - error, mean + error, alpha=0.2, color=line.get_color())
        axes[0].set_xlabel("questions asked")
        axes[1].set_xlabel("turn")
        for axis in axes:
            axis.set_ylabel("held-out accuracy")
            axis.grid(alpha=0.3)
        axes[1].legend(fontsize=8, loc="lower right")
        figure.suptitle(f"{suite.name}: {condition.name} (budget {condition.budget:g}, {condition.turns} turns, "
                        f"change every {condition.change_every}); mean ± standard error")
        path = out / f"curves-{condition.name}.png"
        figure.tight_layout()
        figure.savefig(path, dpi=110)
        plt.close(figure)
        paths.append(path)
    return paths


def plot_question_timing(results: list[dict], suite: Suite, out: Path) -> list[Path]:
    """When each strategy asked, in the first data set's episode (like the thesis's figure 6.7)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    groups = group_results(results)
    for condition in suite.conditions:
        figure, axis = plt.subplots(figsize=(12, 0.5 + 0.45 * len(suite.strategies)))
        for change in range(1, condition.turns + 1, condition.change_every):
            axis.axvline(change, color="0.85", linewidth=0.8, zorder=0)
        for row, strategy in enumerate(suite.strategies):
            group = groups.get((condition.name, strategy), [])
            if not group:
                continue
            series = group[0]["series"]
            asked = np.diff(np.concatenate([[0], series["questions"]])) > 0
            turns = np.asarray(series["turn"])[asked]
            axis.scatter(turns, np.full(len(turns), row), s=9)
        axis.set_yticks(range(len(suite.strategies)), suite.strategies, fontsize=8)
        axis.set_xlabel("turn (grey lines: the scene changes)")
        axis.set_title(f"{suite.name}: {condition.name}: turns on which each strategy asked")
        path = out / f"timing-{condition.name}.png"
        figure.tight_layout()
        figure.savefig(path, dpi=110)
        plt.close(figure)
        paths.append(path)
    return paths


def _fmt_p(p: float) -> str:
    return f"{p:.3g}" if p >= 1e-4 else f"{p:.1e}"


def markdown_report(suite: Suite, results: list[dict], summaries: list[CheckpointSummary],
                    findings: list[FindingResult], seconds: float, out: Path, figures: list[Path]) -> Path:
    axis_name = "questions asked" if suite.axis == "questions" else "turns"
    lines = [f"# Regression report: {suite.name}", "", suite.description, "",
             f"- task `{suite.task}`, kitchen `{suite.kitchen}`, {suite.datasets} training data sets, "
             f"seeds {list(suite.seeds)}, teacher {suite.teacher or {'kind': 'scripted'}}",
             f"- {len(results)} episodes in {seconds:.1f} s of wall time "
             f"({sum(r['seconds'] for r in results):.1f} s of episode time)",
             "- per-episode CSV: [episodes.csv](episodes.csv) (one row per episode, linking its per-turn CSV)", ""]
    for condition in suite.conditions:
        lines += [f"## Condition `{condition.name}`: budget {condition.budget:g}, {condition.turns} turns, "
                  f"a new scene every {condition.change_every} turns", ""]
        lines += [f"![learning curves](curves-{condition.name}.png)", "",
                  f"![when each strategy asked](timing-{condition.name}.png)", ""]
        header = "| strategy | " + " | ".join(f"{c}" for c in suite.checkpoints) + " | questions | demo share |"
        lines += [f"Mean held-out accuracy ± standard error after this many {axis_name}:", "", header,
                  "|---" * (len(suite.checkpoints) + 3) + "|"]
        groups = group_results(results)
        for summary in (s for s in summaries if s.condition == condition.name):
            group = groups[(condition.name, summary.strategy)]
            questions = np.mean([r["series"]["questions"][-1] for r in group])
            demo_cost = np.mean([r["series"]["demo"][-1] * suite.costs.get("demo", 2) /
                                 max(r["series"]["spent"][-1], 1e-9) for r in group])
            cells = " | ".join(f"{m:.3f} ± {e:.3f}" for m, e in zip(summary.mean, summary.error))
            lines.append(f"| {summary.strategy} | {cells} | {questions:.1f} | {demo_cost:.0%} |")
        column = len(suite.checkpoints) - 1
        lines += ["", f"Two-sided Mann-Whitney U between strategies at {suite.checkpoints[column]} {axis_name}:", "",
                  "| a | b | mean a | mean b | U | p |", "|---|---|---|---|---|---|"]
        for c in pairwise(summaries, condition.name, column):
            lines.append(f"| {c.a} | {c.b} | {c.mean_a:.3f} | {c.mean_b:.3f} | {c.u:.1f} | {_fmt_p(c.p)} |")
        lines.append("")
    if findings:
        lines += ["## The thesis's findings, tested here", "",
                  "| finding | condition | at | comparison | mean | U | p (one-tailed) | holds? |",
                  "|---|---|---|---|---|---|---|---|"]
        for outcome in findings:
            f = outcome.finding
            for c in outcome.comparisons:
                lines.append(f"| {f.id}: {f.text} | {f.condition} | {f.at} | {c.a} > {c.b} | "
                             f"{c.mean_a:.3f} vs {c.mean_b:.3f} | {c.u:.1f} | {_fmt_p(c.p)} | "
                             f"{'yes' if c.significant else 'no'} |")
        lines += ["", "Summary: " + "; ".join(f"{o.finding.id} {'holds' if o.holds else 'does not hold'}"
                                               for o in findings) + ".", ""]
        if suite.analysis:
            lines += [f"Why each finding holds or not, and what differs from the thesis: {suite.analysis}", ""]
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
