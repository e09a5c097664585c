"""One suite on several rendered data sets (``regress --data-seeds 0 1 2 3 4``): per data seed and pooled.

Each data seed is a run of its own (its pools rendered from that seed, its own
report in ``data-seed-N/``). The pooled test pairs every episode two
strategies share across all the data seeds (unit: the episode pair; the
interval resamples the training pools of every data seed, the independent
units), with Holm's correction over the suite's findings as in one run.
``replication.md`` puts each finding's verdict per data seed beside the pooled one.
"""

from __future__ import annotations

from pathlib import Path

from dialog.experiments.analysis import FindingResult, evaluate_findings, summarise
from dialog.experiments.kinds import SuiteRun
from dialog.experiments.report import _fmt_p
from dialog.experiments.suite import Suite
from learning.significance import PairedComparison


def pooled_findings(suite: Suite, runs: dict[int, SuiteRun]) -> list[FindingResult]:
    """The suite's findings tested once over the episodes of every data seed (paired, clustered, Holm)."""
    results = [result for run in runs.values() for result in run.data]
    return evaluate_findings(summarise(results, suite), suite)


def _verdict(outcome: FindingResult) -> str:
    if outcome.skipped:
        return "not tested"
    worst = max((c.p if c.p_holm is None else c.p_holm) for c in outcome.comparisons)
    return f"{'holds' if outcome.holds else 'does not hold'} (Holm p ≤ {_fmt_p(worst)})"


def _pooled_cells(outcome: FindingResult) -> str:
    paired = [c for c in outcome.comparisons if isinstance(c, PairedComparison)]
    if not paired:
        return "– | –"
    pairs = min(c.n for c in paired)
    effects = ", ".join(f"{c.b} {c.effect:+.2f} [{c.ci[0]:+.3f}, {c.ci[1]:+.3f}]" for c in paired)
    return f"{pairs} | {effects}"


def replication_report(suite: Suite, runs: dict[int, SuiteRun], pooled: list[FindingResult], out: Path,
                       command: str) -> Path:
    """``replication.md``: every finding's verdict on each data seed and pooled over all of them."""
    seeds = sorted(runs)
    episodes = sum(run.count for run in runs.values())
    lines = [f"# Replication of `{suite.name}` on data seeds {', '.join(map(str, seeds))}", "",
             f"Command: `{command}`. {episodes} episodes in {sum(r.seconds for r in runs.values()):.1f} s; each "
             "data seed's own report is in `data-seed-N/report.md`.", "",
             "Per data seed: the paired tests of that run, Holm-corrected over its findings. Pooled: the same "
             "tests over the episode pairs of every data seed (the unit of the test is one episode pair; the "
             "interval is a cluster bootstrap over the training pools of all data seeds), Holm-corrected over "
             "the findings.", "",
             "| finding | " + " | ".join(f"data seed {s}" for s in seeds) + " | pooled | pooled pairs | "
             "pooled effect r [95 % CI of the mean difference] per comparison |",
             "|---" * (len(seeds) + 4) + "|"]
    by_seed = {seed: {o.finding.id: o for o in run.findings} for seed, run in runs.items()}
    for outcome in pooled:
        cells = [(_verdict(by_seed[s][outcome.finding.id]) if outcome.finding.id in by_seed[s] else "not run")
                 for s in seeds]
        lines.append(f"| {outcome.finding.id}: {outcome.finding.text} | " + " | ".join(cells)
                     + f" | {_verdict(outcome)} | {_pooled_cells(outcome)} |")
    path = out / "replication.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
