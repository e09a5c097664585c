"""One suite on several rendered data sets (``regress --data-seeds 0 1 2 3 4``): per data seed and pooled.

Each data seed is a run of its own (its pools rendered from that seed, its own
report in ``data-seed-N/``). The pooled test pairs every episode two
strategies share across all the data seeds (unit: the episode pair; the
interval resamples whole data seeds, whose episodes share a test pool), with
Holm's correction over the suite's findings as in one run.
``replication.md`` puts each finding's verdict per data seed beside the pooled one;
``replication.json`` holds the same numbers for ``scripts/experiments.py``, which
writes the docs' tables from it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from bullet_world.catalogue import load_task
from dialog.experiments.analysis import FindingResult, evaluate_findings, group_results, summarise
from dialog.experiments.kinds import SuiteRun
from dialog.experiments.quiet import quiet_cells, quiet_table
from dialog.experiments.report import _fmt_p, interval_in_words, questions_and_demo_share, turns_used
from dialog.experiments.suite import Suite
from learning.significance import PairedComparison


def pooled_findings(suite: Suite, runs: dict[int, SuiteRun]) -> list[FindingResult]:
    """The suite's findings tested once over the episodes of every data seed (paired, clustered, Holm)."""
    results = [result for run in runs.values() for result in run.data]
    return evaluate_findings(summarise(results, suite), suite)


def _worst_holm_p(outcome: FindingResult) -> float:
    """The largest Holm-corrected p of a finding's comparisons (the uncorrected p where none was corrected)."""
    return max((c.p if c.p_holm is None else c.p_holm) for c in outcome.comparisons)


def _verdict(outcome: FindingResult) -> str:
    if outcome.skipped:
        return "not tested"
    return f"{'holds' if outcome.holds else 'does not hold'} (Holm p ≤ {_fmt_p(_worst_holm_p(outcome))})"


def _pooled_cells(outcome: FindingResult) -> str:
    paired = [c for c in outcome.comparisons if isinstance(c, PairedComparison)]
    if not paired:
        return "– | –"
    pairs = min(c.n for c in paired)
    effects = ", ".join(f"{c.b} {c.effect:+.2f} {interval_in_words(c)}" for c in paired)
    return f"{pairs} | {effects}"


def replication_report(suite: Suite, runs: dict[int, SuiteRun], pooled: list[FindingResult], out: Path,
                       command: str) -> Path:
    """``replication.md``: every finding's verdict on each data seed and pooled over all of them; per condition
    the quiet turns with budget left, pooled."""
    seeds = sorted(runs)
    episodes = sum(run.count for run in runs.values())
    lines = [f"# Replication of `{suite.name}` on data seeds {', '.join(map(str, seeds))}", "",
             f"Command: `{command}`. {episodes} episodes in {sum(r.seconds for r in runs.values()):.1f} s; each "
             "data seed's own report is in `data-seed-N/report.md`.", "",
             "Per data seed: the paired tests of that run, Holm-corrected over its findings. Pooled: the same "
             "tests over the episode pairs of every data seed (the unit of the test is one episode pair; the "
             "interval is a cluster bootstrap over the data seeds, whose episodes share a test pool, with the "
             "number of clusters beside it), Holm-corrected over the findings.", "",
             "| finding | " + " | ".join(f"data seed {s}" for s in seeds) + " | pooled | pooled pairs | "
             "pooled effect r [95 % CI of the mean difference] per comparison |",
             "|---" * (len(seeds) + 4) + "|"]
    by_seed = {seed: {o.finding.id: o for o in run.findings} for seed, run in runs.items()}
    for outcome in pooled:
        cells = [(_verdict(by_seed[s][outcome.finding.id]) if outcome.finding.id in by_seed[s] else "not run")
                 for s in seeds]
        lines.append(f"| {outcome.finding.id}: {outcome.finding.text} | " + " | ".join(cells)
                     + f" | {_verdict(outcome)} | {_pooled_cells(outcome)} |")
    groups = group_results([result for run in runs.values() for result in run.data])
    for condition in suite.conditions:
        strategies = [strategy for (name, strategy) in groups if name == condition.name]
        lines += ["", f"## Condition `{condition.name}`, pooled over the data seeds", "",
                  *quiet_table(groups, condition.name, strategies)]
    path = out / "replication.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _direction(outcome: FindingResult) -> bool:
    """Every comparison of the finding points its way (mean difference on the finding's side)."""
    if outcome.skipped or not outcome.comparisons:
        return False
    sign = -1.0 if outcome.finding.alternative == "less" else 1.0
    return all(sign * (c.mean_a - c.mean_b) > 0 for c in outcome.comparisons)


def _finding_cell(outcome: FindingResult) -> dict:
    if outcome.skipped:
        return {"tested": False, "why": outcome.skipped}
    return {"tested": True, "holds": outcome.holds, "direction": _direction(outcome),
            "p": max(c.p for c in outcome.comparisons),
            "p_holm": _worst_holm_p(outcome),
            "pairs": min(getattr(c, "n", 0) for c in outcome.comparisons),
            "comparisons": [{"than": c.b, "mean": c.mean_a, "mean_than": c.mean_b,
                             "effect_r": getattr(c, "effect", None), "ci": list(getattr(c, "ci", None) or ()),
                             "clusters": getattr(c, "clusters", None)}
                            for c in outcome.comparisons]}


def _cell(group: list[dict], summary, suite: Suite) -> dict:
    questions, share = questions_and_demo_share(group, suite)
    return {"mean": float(summary.mean[-1]), "error": float(summary.error[-1]), "episodes": len(group),
            "questions": questions, "demo_share": share, **quiet_cells(group), **turns_used(group)}


def replication_summary(suite: Suite, runs: dict[int, SuiteRun], pooled: list[FindingResult], command: str) -> dict:
    """The numbers of ``replication.md`` as data: per condition and strategy the accuracy at the condition's
    last checkpoint (mean ± standard error over episodes), questions, demonstration share and the quiet turns
    with budget left (``quiet.quiet_cells``), per data seed
    and pooled; per finding its test per data seed and pooled."""
    results = [result for run in runs.values() for result in run.data]
    pooled_groups, pooled_summaries = group_results(results), summarise(results, suite)
    scene_default = load_task(suite.task).objects_per_scene
    seed_groups = {seed: group_results(run.data) for seed, run in runs.items()}
    seed_summaries = {seed: {(s.condition, s.strategy): s for s in run.summaries} for seed, run in runs.items()}
    conditions = []
    for condition in suite.conditions:
        rows = []
        for summary in (s for s in pooled_summaries if s.condition == condition.name):
            key = (condition.name, summary.strategy)
            row = {"strategy": summary.strategy, "at": int(summary.checkpoints[-1]) if summary.checkpoints else None,
                   "pooled": _cell(pooled_groups[key], summary, suite), "by_data_seed": {}}
            for seed in runs:
                mine = seed_summaries[seed].get(key)
                if mine is not None and mine.checkpoints:
                    row["by_data_seed"][str(seed)] = _cell(seed_groups[seed][key], mine, suite)
            rows.append(row)
        conditions.append({"name": condition.name, "budget": condition.budget, "turns": condition.turns,
                           "seconds": condition.seconds, "change_every": condition.change_every,
                           "until_budget_spent": condition.until_budget_spent,
                           "objects_per_scene": condition.scene_size(scene_default),
                           "teacher": dict(condition.teacher), "strategies": rows})
    by_seed = {seed: {o.finding.id: o for o in run.findings} for seed, run in runs.items()}
    findings = [{"id": o.finding.id, "text": o.finding.text, "condition": o.finding.condition, "at": o.finding.at,
                 "pooled": _finding_cell(o),
                 "by_data_seed": {str(s): _finding_cell(by_seed[s][o.finding.id]) for s in runs
                                  if o.finding.id in by_seed[s]}} for o in pooled]
    return {"suite": suite.name, "task": suite.task, "axis": suite.axis, "seeds": list(suite.seeds),
            "datasets": suite.datasets, "data_seeds": sorted(runs), "command": command,
            "episodes": sum(run.count for run in runs.values()),
            "seconds": round(sum(run.seconds for run in runs.values()), 2),
            "conditions": conditions, "findings": findings}


def write_replication_json(summary: dict, out: Path) -> Path:
    path = out / "replication.json"
    path.write_text(json.dumps(summary, indent=1, default=_plain) + "\n", encoding="utf-8")
    return path


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")
