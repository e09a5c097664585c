"""Write a recipes suite's results: CSV of every trial, figures, and a Markdown report with the findings.

The report states each chapter-4 finding of ``THESIS_MAP.md`` that the suite
lists, with the one-tailed Mann-Whitney U test behind it, and says plainly
when one does not hold; diagnostic tables (objects against locations, pairs
by lighting) give the material to explain why.
"""

from __future__ import annotations

import csv
from collections import defaultdict
from pathlib import Path

import numpy as np

from dialog.experiments.analysis import CheckpointSummary, FindingResult
from dialog.experiments.recipes import kitchen_pairs
from dialog.experiments.recipes.figures import (
    markdown_cv,
    markdown_transfer,
    plot_cross_validation,
    plot_transfer,
    pyplot,
)
from dialog.experiments.recipes.study import varied_thirds
from dialog.experiments.recipes.suite import RecipeStudy, run_mean
from dialog.experiments.report import _fmt_p, skipped_findings_lines
from dialog.experiments.suite import Suite
from learning.recipes.format import load_builtin_recipe, recipe_parameters
from learning.significance import mann_whitney, mean_and_standard_error

RUN_FIELDS = ("experiment", "seed", "recipe", "kitchen", "trained_in", "m", "repeat", "train_demos", "distance_m",
              "lightings", "parameter", "parameter_kind", "accuracy")
STEP_FIELDS = ("seed", "recipe", "kitchen", "trial", "lighting", "m", "step", "status", "chosen_kind",
               "correct_object", "in_true_end_region", "success")


def write_run_csvs(results: dict, out: Path) -> list[Path]:
    """``runs.csv``: one row per trained grounding and parameter; ``execution.csv``: one row per executed step."""
    out.mkdir(parents=True, exist_ok=True)
    kinds = {}
    with open(out / "runs.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=RUN_FIELDS)
        writer.writeheader()
        for experiment in ("cv", "pairs", "transfer"):
            for result in results[experiment]:
                if result["recipe"] not in kinds:
                    parameters = recipe_parameters(load_builtin_recipe(result["recipe"]))
                    kinds[result["recipe"]] = {**dict.fromkeys(parameters.objects, "object"),
                                               **dict.fromkeys(parameters.locations, "location")}
                for run in result["runs"]:
                    common = {"experiment": experiment, "seed": result["seed"], "recipe": result["recipe"],
                              "kitchen": run.get("test", result["kitchen"]),
                              "trained_in": "+".join(run.get("train", [result["kitchen"]]))
                              if experiment == "transfer" else result["kitchen"],
                              "m": run.get("m", 2), "repeat": run.get("repeat", ""),
                              "train_demos": " ".join(str(i + 1) for i in run.get("pair", run.get("train", [])))
                              if experiment != "transfer" else "",
                              "distance_m": f"{run['distance_m']:.4f}" if "distance_m" in run else "",
                              "lightings": run.get("lightings", "")}
                    for name, value in run["accuracy"].items():
                        writer.writerow({**common, "parameter": name, "parameter_kind": kinds[result["recipe"]][name],
                                         "accuracy": f"{value:.4f}"})
    with open(out / "execution.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=STEP_FIELDS)
        writer.writeheader()
        for result in results["collect"]:
            for run in result["runs"]:
                for step in run["steps"]:
                    writer.writerow({"seed": result["seed"], "recipe": result["recipe"], "kitchen": result["kitchen"],
                                     "trial": run["trial"], "lighting": run["lighting"], "m": run["m"], **step})
    return [out / "runs.csv", out / "execution.csv"]


def _cv_curves(results: dict, recipe: str, m_values) -> dict[str, dict[str, list[float]]]:
    """Mean accuracy per kitchen and parameter at every m (all seeds pooled)."""
    curves: dict[str, dict[str, list[float]]] = {}
    for result in (r for r in results["cv"] if r["recipe"] == recipe):
        runs = result["runs"]
        names = list(runs[0]["accuracy"])
        per_kitchen = curves.setdefault(result["kitchen"], {name: [] for name in names})
        for name in names:
            per_kitchen[name].append([np.mean([r["accuracy"][name] for r in runs if r["m"] == m]) for m in m_values])
    return {k: {n: list(np.mean(v, axis=0)) for n, v in per.items()} for k, per in curves.items()}


def _transfer_rows(results: dict, recipe: str) -> list[dict]:
    """Mean accuracy per (m, training kitchens, test kitchen), as in figure 4.8."""
    groups: dict[tuple, list[dict]] = defaultdict(list)
    for result in (r for r in results["transfer"] if r["recipe"] == recipe):
        for run in result["runs"]:
            groups[(run["m"], tuple(run["train"]), run["test"])].append(run)
    rows = []
    for (m, train, test), runs in sorted(groups.items(), key=lambda item: (item[0][0], len(item[0][1]), item[0])):
        mean = {name: float(np.mean([r["accuracy"][name] for r in runs])) for name in runs[0]["accuracy"]}
        rows.append({"m": m, "train": list(train), "test": test, "situated": test in train, "accuracy": mean,
                     "mean": float(np.mean(list(mean.values())))})
    return rows


def _split(runs: list[dict], kinds: dict[str, str]) -> str:
    """Mean ± standard error of the object and of the location parameters over ``runs``."""
    cells = []
    for kind in ("object", "location"):
        values = np.array([[np.mean([v for n, v in r["accuracy"].items() if kinds[n] == kind])] for r in runs])
        mean, error = mean_and_standard_error(values)
        cells.append(f"{mean[0]:.3f} ± {error[0]:.3f}")
    return " | ".join(cells)


def plot_overview(summaries: list[CheckpointSummary], recipe: str, path: Path) -> None:
    """Every arm of one recipe against m: the learning curve, the varied pairs, the transfer, the execution."""
    plt = pyplot()
    figure, axis = plt.subplots(figsize=(7.5, 4.2))
    styles = {"cross-validation": ("-", "o", "tab:blue"), "most-varied": ("", "^", "tab:green"),
              "least-varied": ("", "v", "tab:olive"), "situated": ("--", "s", "tab:red"),
              "elsewhere": ("--", "D", "tab:purple"), "execution": ("", "*", "black"),
              "kitchen-pairs": (":", "P", "tab:brown")}
    for summary in (s for s in summaries if s.condition == recipe):
        line, marker, colour = styles[summary.strategy]
        axis.errorbar(summary.checkpoints, summary.mean, yerr=summary.error, linestyle=line or "none", marker=marker,
                      color=colour, capsize=3, label=f"{summary.strategy} (n={len(summary.values)})")
    axis.set_xlabel("training demonstrations m (per kitchen)")
    axis.set_ylabel("mean accuracy over the parameters")
    axis.set_ylim(-0.02, 1.05)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=8, loc="lower right")
    axis.set_title(f"{recipe}: mean ± standard error")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def _findings_table(findings: list[FindingResult]) -> list[str]:
    lines = ["| finding | recipe | comparison | mean | U | p (one-tailed) | holds? |", "|---|---|---|---|---|---|---|"]
    for outcome in findings:
        f = outcome.finding
        for c in outcome.comparisons:
            margin = f" + {f.margin:g}" if f.margin else ""
            lines.append(f"| {f.id}: {f.text} | {f.condition} | {c.a}{margin} > {c.b} | {c.mean_a:.3f} vs "
                         f"{c.mean_b:.3f} | {c.u:.1f} | {_fmt_p(c.p)} | {'yes' if c.significant else 'no'} |")
    lines += ["", *skipped_findings_lines(findings), "Summary: " + "; ".join(
        f"{o.finding.id} {'does NOT hold' if not o.holds and not o.skipped else o.verdict}" for o in findings) + ".",
        ""]
    for outcome in (o for o in findings if not o.holds and not o.skipped):
        f = outcome.finding
        for c in outcome.comparisons:
            direction = "higher" if c.mean_a > c.mean_b else "lower" if c.mean_a < c.mean_b else "equal"
            lines.append(f"- **{f.id} does not hold**: {c.a} averages {c.mean_a:.3f}, {direction} than {c.b} "
                         f"({c.mean_b:.3f}){f' with a margin of {f.margin:g}' if f.margin else ''}; one-tailed "
                         f"p = {_fmt_p(c.p)} over {c.n_a} and {c.n_b} trials. The diagnostics below give the "
                         "material to explain it.")
    return lines + [""]


def write_recipe_report(suite: Suite, study: RecipeStudy, results: dict, summaries: list[CheckpointSummary],
                        findings: list[FindingResult], seconds: float, out: Path, trials: int) -> Path:
    """CSV files, figures and ``report.md`` in ``out``; returns the report's path."""
    write_run_csvs(results, out)
    lines = [f"# Regression report: {suite.name}", "", suite.description, "",
             f"- recipes {', '.join(study.recipes)}; kitchens {', '.join(study.kitchens)}; seeds {list(study.seeds)}",
             f"- within each kitchen: {study.demos} demonstrations (the sweep's arrangements under each lighting), "
             f"{study.cv_repeats} random training sets per m; transfer: the first {study.transfer_demos} "
             f"demonstrations of each kitchen, m from each training kitchen, {study.transfer_repeats} repetitions; "
             f"execution trials with the arm per recipe and kitchen: {study.execution_trials}",
             f"- {trials} trials (trained groundings and executed recipes) in {seconds:.1f} s of wall time",
             "- every trial: [runs.csv](runs.csv) (one row per parameter); executed steps: "
             "[execution.csv](execution.csv)"]
    if suite.analysis:
        lines.append(f"- written analysis of the findings: {suite.analysis}")
    lines.append("")
    if findings:
        lines += ["## The thesis's chapter-4 findings, tested here", ""] + _findings_table(findings)
    for recipe in study.recipes:
        kinds = {**dict.fromkeys(recipe_parameters(load_builtin_recipe(recipe)).objects, "object"),
                 **dict.fromkeys(recipe_parameters(load_builtin_recipe(recipe)).locations, "location")}
        plot_overview(summaries, recipe, out / f"overview-{recipe}.png")
        lines += [f"## {recipe}", "", f"![every arm against m](overview-{recipe}.png)", "",
                  "| arm | " + " | ".join(f"m={m}" for m in sorted({m for s in summaries if s.condition == recipe
                                                                          for m in s.checkpoints})) + " | trials |"]
        all_m = sorted({m for s in summaries if s.condition == recipe for m in s.checkpoints})
        lines.append("|---|" + "---:|" * (len(all_m) + 1))
        for s in (s for s in summaries if s.condition == recipe):
            cells = [f"{s.mean[s.checkpoints.index(m)]:.3f} ± {s.error[s.checkpoints.index(m)]:.3f}"
                     if m in s.checkpoints else "" for m in all_m]
            lines.append(f"| {s.strategy} | " + " | ".join(cells) + f" | {len(s.values)} |")
        lines.append("")
        lines += _cross_validation_section(results, recipe, study, kinds, out)
        lines += _pairs_section(results, recipe, kinds)
        lines += _transfer_section(results, recipe, study, kinds, out)
        lines += _execution_section(results, recipe)
        if study.runs("kitchen-pairs"):
            lines += kitchen_pairs.section(results, recipe, study, out)
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _cross_validation_section(results, recipe, study, kinds, out) -> list[str]:
    cv = [r for r in results["cv"] if r["recipe"] == recipe]
    if not cv:
        return []
    m_values = list(study.cv_m)
    curves = _cv_curves(results, recipe, m_values)
    objects = tuple(name for name, kind in kinds.items() if kind == "object")
    plot_cross_validation(curves, objects, out / f"cv-{recipe}.png", recipe, m_values)
    runs = [run for r in cv for run in r["runs"]]
    lines = ["### Within-kitchen cross-validation (figure 4.6 shape)", "", f"![per parameter](cv-{recipe}.png)", "",
             "Objects against locations (mean ± standard error over kitchens and training sets):", "",
             "| m | objects | locations |", "|---:|---:|---:|"]
    lines += [f"| {m} | {_split([r for r in runs if r['m'] == m], kinds)} |" for m in m_values]
    lines.append("")
    for kitchen, per_parameter in curves.items():
        lines += [markdown_cv(kitchen, per_parameter, recipe, m_values), ""]
    return lines


def _pairs_section(results, recipe, kinds) -> list[str]:
    pairs = [r for r in results["pairs"] if r["recipe"] == recipe]
    if not pairs:
        return []
    lines = ["### Two demonstrations: varied against similar pairs (eq. 4.4, figure 4.7)", "",
             "| kitchen | pairs | least varied: distance, objects, locations | most varied: distance, objects, "
             "locations | p (most > least, one-tailed) |", "|---|---:|---|---|---:|"]
    both, one, varied_both = [], [], []
    for result in pairs:
        least, most = varied_thirds(result["runs"])
        test = mann_whitney("most", [run_mean(r) for r in most], "least", [run_mean(r) for r in least], "greater")
        lines.append(f"| {result['kitchen']} (seed {result['seed']}) | {len(result['runs'])} | "
                     f"{np.mean([r['distance_m'] for r in least]):.2f} m, {_split(least, kinds).replace(' | ', ', ')}"
                     f" | {np.mean([r['distance_m'] for r in most]):.2f} m, "
                     f"{_split(most, kinds).replace(' | ', ', ')} | {_fmt_p(test.p)} |")
        covering = [r for r in result["runs"] if r["lightings"] == 2]
        both += covering
        one += [r for r in result["runs"] if r["lightings"] == 1]
        if covering:
            varied_both += varied_thirds(covering)[1]
    lines.append("")
    if both and one:
        test = mann_whitney("both", [run_mean(r) for r in both], "one", [run_mean(r) for r in one], "greater")
        lines += ["Pairs by lighting (objects, locations): both lightings "
                  f"{_split(both, kinds).replace(' | ', ', ')} ({len(both)} pairs); one lighting "
                  f"{_split(one, kinds).replace(' | ', ', ')} ({len(one)} pairs); both > one on the mean over "
                  f"parameters: one-tailed p = {_fmt_p(test.p)}. The most varied third of the pairs that cover "
                  f"both lightings: {_split(varied_both, kinds).replace(' | ', ', ')}, mean over parameters "
                  f"{np.mean([run_mean(r) for r in varied_both]):.3f}; the best single pair "
                  f"{max(run_mean(r) for r in both):.3f}.", ""]
    return lines


def _transfer_section(results, recipe, study, kinds, out) -> list[str]:
    rows = _transfer_rows(results, recipe)
    if not rows:
        return []
    plot_transfer(rows, study.kitchens[0], out / f"transfer-{recipe}.png", recipe)
    runs = [run for r in results["transfer"] if r["recipe"] == recipe for run in r["runs"]]
    lines = ["### Transfer between kitchens (figure 4.8 shape)", "",
             f"![tested in {study.kitchens[0]}](transfer-{recipe}.png)", "",
             "| m | trained with the test kitchen: objects, locations | only elsewhere: objects, locations | "
             "best elsewhere | worst situated |", "|---:|---|---|---:|---:|"]
    for m in study.transfer_m:
        situated = [r for r in runs if r["m"] == m and r["situated"]]
        elsewhere = [r for r in runs if r["m"] == m and not r["situated"]]
        best_out = max(row["mean"] for row in rows if row["m"] == m and not row["situated"])
        worst_in = min(row["mean"] for row in rows if row["m"] == m and row["situated"])
        lines.append(f"| {m} | {_split(situated, kinds).replace(' | ', ', ')} | "
                     f"{_split(elsewhere, kinds).replace(' | ', ', ')} | {best_out:.2f} | {worst_in:.2f} |")
    lines += ["", "Mean accuracy of every set of training kitchens in every test kitchen (bold: trained with "
              "demonstrations from the test kitchen):", "", markdown_transfer(rows), ""]
    return lines


def _execution_section(results, recipe) -> list[str]:
    runs = [(r["kitchen"], run) for r in results["collect"] if r["recipe"] == recipe for run in r["runs"]]
    if not runs:
        return []
    lines = ["### Execution with the arm (grounded on every demonstration)", "",
             "| kitchen | trials | steps carried out correctly | other outcomes |", "|---|---:|---:|---|"]
    for kitchen in dict.fromkeys(k for k, _ in runs):
        steps = [step for k, run in runs if k == kitchen for step in run["steps"]]
        other = defaultdict(int)
        for step in steps:
            if not step["success"]:
                other[step["status"] if step["status"] != "done" else "done, but wrong object or place"] += 1
        lines.append(f"| {kitchen} | {sum(k == kitchen for k, _ in runs)} | "
                     f"{sum(s['success'] for s in steps)} of {len(steps)} | "
                     f"{', '.join(f'{k} {v}' for k, v in other.items()) or 'none'} |")
    return lines + [""]
