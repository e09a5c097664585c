"""Write an episodes suite's results: per-episode CSV, tables and a Markdown report (figures: ``figures.py``)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from bullet_world.catalogue import load_task
from dialog.experiments.analysis import CheckpointSummary, FindingResult, group_results, pairwise
from dialog.experiments.episodes import SERIES
from dialog.experiments.quiet import quiet_columns, quiet_table
from dialog.experiments.suite import Suite
from learning.significance import PairedComparison
from learning.strategies import file_label


def write_episode_csvs(results: list[dict], out: Path) -> Path:
    """One CSV per episode (turn, accuracy, questions by type, budget) and one summary row per episode, ending
    with its quiet turns with budget left and DT's mean terms on them (``quiet.quiet_columns``)."""
    summary_path = out / "episodes.csv"
    out.mkdir(parents=True, exist_ok=True)
    with open(summary_path, "w", newline="") as summary_file:
        summary = csv.writer(summary_file)
        summary.writerow(["condition", "strategy", "dataset", "seed", "accuracy", "questions", "label", "demo",
                          "feature", "spent", "seconds", "csv", "quiet_with_budget_left", "quiet_terms", "turns",
                          "ended"])
        for result in results:
            spec, series = result["spec"], result["series"]
            path = out / "episodes" / spec["condition"]["name"] / f"{file_label(spec['strategy'])}" \
                f"-d{spec['dataset']}-s{spec['seed']}.csv"  # as the transcript is named: no ':' or '/' in it
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(path, "w", newline="") as handle:
                writer = csv.writer(handle)
                writer.writerow(SERIES)
                writer.writerows(zip(*(series[name] for name in SERIES)))
            summary.writerow([spec["condition"]["name"], spec["strategy"], spec["dataset"], spec["seed"],
                              f"{result['accuracy']:.4f}", series["questions"][-1], series["label"][-1],
                              series["demo"][-1], series["feature"][-1], series["spent"][-1],
                              f"{result['seconds']:.2f}", path.relative_to(out), *quiet_columns(result),
                              len(series["turn"]), result.get("ended", "")])
    return summary_path


def questions_and_demo_share(group: list[dict], suite: Suite) -> tuple[float, float]:
    """Mean questions asked per episode, and the mean share of the spent budget that went on demonstrations."""
    questions = float(np.mean([r["series"]["questions"][-1] for r in group]))
    share = float(np.mean([r["series"]["demo"][-1] * suite.costs.get("demo", 2) / max(r["series"]["spent"][-1], 1e-9)
                           for r in group]))
    return questions, share


def turns_used(group: list[dict]) -> dict:
    """Turns the episodes of a group played: mean, median, and how many ended at the safety bound (chapter-6
    conditions that run until the budget is spent; ``EpisodeResult.ended``)."""
    turns = [len(r["series"]["turn"]) for r in group]
    return {"turns_mean": float(np.mean(turns)), "turns_median": float(np.median(turns)),
            "at_bound": sum(r.get("ended") == "bound" for r in group)}


def until_budget_spent_in_words(condition) -> str:
    """How a condition that ends on its budget reads in a heading (the bound in turns)."""
    return f"until the budget is spent (bound {condition.turns} turns), "


def _fmt_p(p: float) -> str:
    """A p value: 3 significant digits, scientific below 1e-4 (one format for the whole column)."""
    return f"{p:.3g}" if p >= 1e-4 else f"{p:.1e}"


PLANNED_NOTE = ("Every strategy played the same episodes (the same pools, seeds and scenes), so each comparison is "
                "paired: the Wilcoxon signed-rank test over the shared episodes (n pairs, treated as independent), "
                "the matched-pairs rank-biserial r, the median difference, and a 95 % interval of the mean "
                "difference from a cluster bootstrap over the data seeds (the episodes of one data seed share its "
                "rendered data and test pool, so a data seed is one cluster; the number of clusters stands beside "
                "each interval, and with one data seed there is no interval). A finding holds when every one of "
                "its comparisons is significant after Holm's correction over all the comparisons in this table.")


def _paired_cells(c) -> str:
    """n | median diff | r | CI | W for a paired comparison; the unpaired Mann-Whitney's n and U otherwise."""
    if isinstance(c, PairedComparison):
        return f"{c.n} | {c.median_difference:+.3f} | {c.effect:+.2f} | {interval_in_words(c)} | {c.statistic:.1f}"
    return f"{c.n_a} + {c.n_b} | – | – | – | U {c.u:.1f}"


def interval_in_words(c: PairedComparison) -> str:
    """"[+0.010, +0.050] (5 clusters)", or "none (1 cluster)" when a single cluster leaves nothing to resample."""
    clusters = f"({c.clusters} cluster{'s' if c.clusters != 1 else ''})"
    return f"none {clusters}" if c.ci is None else f"[{c.ci[0]:+.3f}, {c.ci[1]:+.3f}] {clusters}"


def comparison_table(comparisons: list, at: str) -> list[str]:
    """Markdown rows of two-sided comparisons between pairs of strategies (paired where they share episodes)."""
    lines = [f"| a | b | mean a {at} | mean b {at} | n | median diff | r | 95 % CI of the mean diff | W | p |",
             "|---" * 10 + "|"]
    for c in comparisons:
        lines.append(f"| {c.a} | {c.b} | {c.mean_a:.3f} | {c.mean_b:.3f} | {_paired_cells(c)} | {_fmt_p(c.p)} |")
    return lines


def skipped_findings_lines(findings: list[FindingResult]) -> list[str]:
    """A Markdown list of the findings that were not tested, each with the reason (empty when none)."""
    skipped = [o for o in findings if o.skipped]
    if not skipped:
        return []
    return ["Skipped findings (not tested in this run):", ""] + [
        f"- {o.finding.id}: {o.finding.text}: skipped, {o.skipped}" for o in skipped] + [""]


def findings_summary_line(findings: list[FindingResult]) -> str:
    return "Summary: " + "; ".join(f"{o.finding.id} {o.verdict}" for o in findings) + "."


def findings_closing_lines(findings: list[FindingResult], analysis: str) -> list[str]:
    """After a findings table: the skipped findings, the summary, and the link to the written analysis."""
    lines = ["", *skipped_findings_lines(findings), findings_summary_line(findings), ""]
    if analysis:
        lines += [f"Why each finding holds or not, and what differs from the thesis: {analysis}", ""]
    return lines


def write_markdown(lines: list[str], out: Path) -> Path:
    """Write ``out/report.md`` from its lines."""
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def numbers_in_words(numbers) -> str:
    """(0, 1, 2, 3, 4) -> "0-4"; (0, 2, 7) -> "0, 2, 7" (as a reader writes seeds, never a Python list)."""
    values = [int(n) for n in numbers]
    if len(values) > 2 and values == list(range(values[0], values[0] + len(values))):
        return f"{values[0]}-{values[-1]}"
    return ", ".join(str(v) for v in values)


def teacher_in_words(teacher: dict) -> str:
    """{} -> "scripted"; {"kind": "scripted", "mislabel_rate": 0.1} -> "scripted (mislabel rate 0.1)"."""
    options = {k: v for k, v in dict(teacher or {}).items() if k != "kind"}
    kind = (teacher or {}).get("kind", "scripted")
    if not options:
        return str(kind)
    return f"{kind} (" + ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in sorted(options.items())) + ")"


def markdown_report(suite: Suite, results: list[dict], summaries: list[CheckpointSummary],
                    findings: list[FindingResult], seconds: float, out: Path, figures: list[Path]) -> Path:
    """``report.md``: per condition the figures, accuracy at the checkpoints inside its turns, the quiet turns
    with budget left (``quiet.py``), pairwise tests at its last checkpoint; then every finding, tested or
    skipped with the reason."""
    axis_name = {"questions": "questions asked", "seconds": "seconds"}.get(suite.axis, "turns")
    lines = [f"# Regression report: {suite.name}", "", suite.description, "",
             f"- task `{suite.task}`, kitchen `{suite.kitchen}`, {suite.datasets} training data sets, "
             f"seeds {numbers_in_words(suite.seeds)}, teacher {teacher_in_words(suite.teacher)}",
             f"- data sets rendered from data seed {suite.data_seed}"
             + (" (the data of the stored baselines)" if suite.data_seed == 0 else " (fresh data: a replication)"),
             *[f"- strategy `{name}`: DT with the weights in {weights.describe()}"
               for name, weights in suite.weights.items()],
             f"- {len(results)} episodes in {seconds:.1f} s of wall time "
             f"({sum(r['seconds'] for r in results):.1f} s of episode time)",
             "- per-episode CSV: [episodes.csv](episodes.csv) (one row per episode, linking its per-turn CSV)", ""]
    figure_names = {path.name for path in figures}
    groups = group_results(results)
    scene_default = load_task(suite.task).objects_per_scene
    for condition in suite.conditions:
        embodied = "" if condition.seconds is None else \
            f"embodied costs, {condition.seconds:g} s (at most {condition.turns} turns), "
        embodied = until_budget_spent_in_words(condition) if condition.until_budget_spent else embodied
        lines += [f"## Condition `{condition.name}`: budget {condition.budget:g}, "
                  f"{embodied or f'{condition.turns} turns, '}a new scene every {condition.change_every} turns, "
                  f"{condition.scene_size(scene_default)} objects a scene"
                  + (f", teacher {teacher_in_words(suite.teacher | dict(condition.teacher))}" if condition.teacher
                     else ""), ""]
        for stem, text in (("curves", "learning curves"), ("timing", "when each strategy asked")):
            if f"{stem}-{condition.name}.png" in figure_names:
                lines += [f"![{text}]({stem}-{condition.name}.png)", ""]
        rows = [s for s in summaries if s.condition == condition.name]
        checkpoints = rows[0].checkpoints if rows else ()
        left_out = [c for c in suite.checkpoints if c not in checkpoints]
        if not checkpoints:
            lines += [f"No checkpoint of the suite ({list(suite.checkpoints)}) lies within this condition's "
                      f"{condition.turns} turns.", ""]
            continue
        note = f" (checkpoints {left_out} lie beyond its {condition.turns} turns)" if left_out else ""
        used = ["used"] if condition.seconds is not None or condition.until_budget_spent else []
        lines += [f"Mean held-out accuracy ± standard error after this many {axis_name}{note}:", "",
                  "| strategy | " + " | ".join([*(f"after {c} {axis_name}" for c in checkpoints), *used])
                  + " | questions | demo share |", "|---" * (len(checkpoints) + 3 + len(used)) + "|"]
        for summary in rows:
            group = groups[(condition.name, summary.strategy)]
            questions, demo_cost = questions_and_demo_share(group, suite)
            cells = " | ".join(f"{m:.3f} ± {e:.3f}" for m, e in zip(summary.mean, summary.error))
            if condition.seconds is not None:  # embodied costs: how many turns and seconds the episodes took
                turns = np.mean([r["series"]["turn"][-1] for r in group])
                cells += f" | {turns:.1f} turns, {np.mean([r['series']['seconds'][-1] for r in group]):.0f} s"
            elif condition.until_budget_spent:  # the thesis's ending: turns taken (mean / median), at the bound
                taken = turns_used(group)
                cells += f" | {taken['turns_mean']:.1f} / {taken['turns_median']:g} turns, {taken['at_bound']} of " \
                         f"{len(group)} at the bound"
            lines.append(f"| {summary.strategy} | {cells} | {questions:.1f} | {demo_cost:.0%} |")
        if condition.until_budget_spent:
            lines += ["", f"Episodes run until the budget is spent; \"used\" gives the turns they took (mean / "
                          f"median), and how many reached the bound of {condition.turns} turns with budget left "
                          "(scored where they stopped)."]
        lines += ["", *quiet_table(groups, condition.name, [summary.strategy for summary in rows])]
        column = len(checkpoints) - 1
        lines += ["", f"Exploratory (not corrected, not planned): two-sided tests between every pair of strategies "
                      f"after {checkpoints[column]} {axis_name}.", ""]
        lines += comparison_table(pairwise(summaries, condition.name, column), f"after {checkpoints[column]}")
        lines.append("")
    if findings:
        lines += ["## The thesis's findings, tested here (planned)", "", PLANNED_NOTE, "",
                  "| finding | condition | compared after | comparison | mean | n | median diff | r | 95 % CI of "
                  "the mean diff | W | p (one-tailed) | p (Holm) | holds? |", "|---" * 13 + "|"]
        for outcome in findings:
            f = outcome.finding
            for c in outcome.comparisons:
                lines.append(f"| {f.id}: {f.text} | {f.condition} | {f.at} {axis_name} | {c.a} > {c.b} | "
                             f"{c.mean_a:.3f} vs {c.mean_b:.3f} | {_paired_cells(c)} | {_fmt_p(c.p)} | "
                             f"{_fmt_p(c.p_holm) if c.p_holm is not None else '–'} | "
                             f"{'yes' if c.significant else 'no'} |")
        lines += findings_closing_lines(findings, suite.analysis)
    return write_markdown(lines, out)
