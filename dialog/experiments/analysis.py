"""From episode results to numbers: accuracy at checkpoints, summaries, finding tests."""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, replace

import numpy as np

from dialog.experiments.suite import Finding, Suite
from learning.significance import (
    Comparison,
    PairedComparison,
    accuracy_after_questions,
    holm,
    mann_whitney,
    mean_and_standard_error,
    wilcoxon_paired,
)

BOOTSTRAP_SEED = 20260  # the cluster bootstrap's own stream: the same results give the same intervals


def condition_checkpoints(suite: Suite, turns: float) -> tuple[int, ...]:
    """The suite's checkpoints a condition of ``turns`` turns can reach (no more questions than turns either);
    on the seconds axis, ``turns`` is the condition's seconds allocation."""
    return tuple(c for c in suite.checkpoints if c <= turns)


def checkpoint_values(result: dict, suite: Suite, checkpoints: tuple[int, ...] | None = None) -> np.ndarray:
    """One episode's accuracy at each checkpoint (default: the suite's), in questions asked or turns.

    An episode that never asked as many questions as a checkpoint (its strategy
    chose to stay quiet, or its time ran out) counts with its final accuracy:
    that is what it learned with what it chose to ask.
    """
    checkpoints = suite.checkpoints if checkpoints is None else checkpoints
    series = result["series"]
    accuracy = np.asarray(series["accuracy"], dtype=float)
    if suite.axis == "questions":
        values = accuracy_after_questions(np.asarray(series["questions"]), accuracy, checkpoints)
        return np.where(np.isnan(values), accuracy[-1], values)
    if suite.axis == "seconds":  # embodied costs: the accuracy of the last turn ended by each checkpoint
        ended = np.asarray(series.get("seconds", series["turn"]), dtype=float)
        return np.array([accuracy[ended <= t][-1] if np.any(ended <= t) else np.nan for t in checkpoints])
    turns = np.asarray(series["turn"])
    return np.array([accuracy[turns <= t][-1] if np.any(turns <= t) else np.nan for t in checkpoints])


def group_results(results: list[dict]) -> dict[tuple[str, str], list[dict]]:
    """Results keyed by (condition, strategy), in run order."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for result in results:
        spec = result["spec"]
        groups[(spec["condition"]["name"], spec["strategy"])].append(result)
    return groups


@dataclass(frozen=True)
class CheckpointSummary:
    condition: str
    strategy: str
    checkpoints: tuple[int, ...]
    mean: np.ndarray
    error: np.ndarray
    values: np.ndarray  # (episodes x checkpoints)
    keys: tuple = ()  # per episode (data seed, data set, seed): what pairs it with another strategy's episode


def summarise(results: list[dict], suite: Suite) -> list[CheckpointSummary]:
    """One summary per (condition, strategy), at the checkpoints inside the condition's turns."""
    summaries = []
    for (condition, strategy), group in group_results(results).items():
        limit = group[0]["spec"]["condition"].get("seconds" if suite.axis == "seconds" else "turns")
        checkpoints = suite.checkpoints if limit is None else condition_checkpoints(suite, limit)
        values = np.vstack([checkpoint_values(r, suite, checkpoints) for r in group]).reshape(len(group), -1)
        mean, error = mean_and_standard_error(values)
        keys = tuple((r["spec"].get("data_seed", 0), r["spec"]["dataset"], r["spec"]["seed"]) for r in group)
        summaries.append(CheckpointSummary(condition, strategy, checkpoints, mean, error, values, keys))
    return summaries


@dataclass(frozen=True)
class FindingResult:
    """A finding's tests; a finding that could not be tested has no comparisons and says why in ``skipped``."""

    finding: Finding
    comparisons: tuple[Comparison | PairedComparison, ...]
    skipped: str = ""

    @property
    def holds(self) -> bool:
        return not self.skipped and bool(self.comparisons) and all(c.significant for c in self.comparisons)

    @property
    def verdict(self) -> str:
        return f"skipped: {self.skipped}" if self.skipped else "holds" if self.holds else "does not hold"


def skipped_by_overrides(original: Suite, suite: Suite) -> list[FindingResult]:
    """The findings of ``original`` that the command-line strategy subset of ``suite`` left out, with the reason."""
    kept = {finding.id for finding in suite.findings}
    skipped = []
    for finding in (f for f in original.findings if f.id not in kept):
        missing = [s for s in (finding.better, *finding.than) if s not in suite.strategies]
        skipped.append(FindingResult(finding, (), f"needs {', '.join(missing)}, not among the strategies run "
                                                  f"({', '.join(suite.strategies)})"))
    return skipped


def evaluate_findings(summaries: list[CheckpointSummary], suite: Suite) -> list[FindingResult]:
    """Each finding tested at its checkpoint as the suite says (one-tailed by default), then Holm's correction
    over every comparison of the suite's findings (the planned tests of one table).

    Strategies that played the same episodes (every episodes suite: same pools, seeds, scenes) are compared
    paired, by the Wilcoxon signed-rank test over the shared episodes with a cluster bootstrap interval over
    the data seeds; summaries without episode keys (chapter 5's users) by Mann-Whitney U. A finding whose
    checkpoint lies beyond its condition's turns, or whose strategies have no results, is skipped with the reason.
    """
    lookup = {(s.condition, s.strategy): s for s in summaries}
    outcomes, tested = [], []
    for finding in suite.findings:
        reason = _untestable(finding, lookup, suite)
        if reason:
            outcomes.append(FindingResult(finding, (), reason))
            continue
        better = lookup[(finding.condition, finding.better)]
        column = better.checkpoints.index(finding.at)
        comparisons = tuple(compare(better, lookup[(finding.condition, other)], column, finding.alternative,
                                    finding.margin) for other in finding.than)
        outcomes.append(FindingResult(finding, comparisons))
        tested.append(len(outcomes) - 1)
    adjusted = iter(holm([c for index in tested for c in outcomes[index].comparisons]))
    for index in tested:
        outcome = outcomes[index]
        outcomes[index] = FindingResult(outcome.finding, tuple(next(adjusted) for _ in outcome.comparisons))
    return outcomes


def compare(first: CheckpointSummary, second: CheckpointSummary, column: int,
            alternative: str = "two-sided", margin: float = 0.0) -> Comparison | PairedComparison:
    """``first`` against ``second`` at one checkpoint: paired over their shared episodes where both have episode
    keys, else Mann-Whitney U over the episodes that reached it. With a ``margin`` (non-inferiority) the test
    is of ``first`` + margin against ``second``; the means, differences and interval reported are the
    strategies' own (without the margin), the effect r is the tested one's.

    The paired interval resamples whole data seeds: the episodes of one data seed share its rendered data and
    its one test pool, so they are one cluster (``PairedComparison.clusters`` says how many; with a single
    data seed there is no interval). The Wilcoxon test treats the pairs as independent."""
    if first.keys and second.keys:
        mine = {key: value for key, value in zip(first.keys, first.values[:, column]) if np.isfinite(value)}
        theirs = {key: value for key, value in zip(second.keys, second.values[:, column]) if np.isfinite(value)}
        shared = [key for key in first.keys if key in mine and key in theirs]
        if shared:
            tested = wilcoxon_paired(first.strategy, [mine[k] + margin for k in shared], second.strategy,
                                     [theirs[k] for k in shared], alternative, clusters=[k[0] for k in shared],
                                     rng=np.random.default_rng(BOOTSTRAP_SEED))
            if not margin:
                return tested
            ci = None if tested.ci is None else (tested.ci[0] - margin, tested.ci[1] - margin)
            return replace(tested, mean_a=tested.mean_a - margin, median_difference=tested.median_difference - margin,
                           ci=ci)
    tested = mann_whitney(first.strategy, _finite(first.values[:, column]) + margin, second.strategy,
                          _finite(second.values[:, column]), alternative)
    return replace(tested, mean_a=tested.mean_a - margin) if margin else tested


def _untestable(finding: Finding, lookup: dict, suite: Suite) -> str:
    """Why ``finding`` cannot be tested with these summaries ("" when it can)."""
    axis = "questions" if suite.axis == "questions" else suite.axis
    for strategy in (finding.better, *finding.than):
        summary = lookup.get((finding.condition, strategy))
        if summary is None:
            return f"no results for {strategy} in condition '{finding.condition}'"
        if finding.at not in summary.checkpoints:
            turns = next((c.turns for c in suite.conditions if c.name == finding.condition), None)
            if turns is not None and finding.at > turns:
                return f"it compares after {finding.at} {axis}, beyond the condition's {turns} turns"
            return f"{finding.at} is not a checkpoint of condition '{finding.condition}' {list(summary.checkpoints)}"
    return ""


def pairwise(summaries: list[CheckpointSummary], condition: str, column: int) -> list:
    """Two-sided tests between every pair of strategies in one condition at one checkpoint (exploratory:
    uncorrected, reported apart from the planned findings)."""
    group = [s for s in summaries if s.condition == condition]
    return [compare(first, second, column) for i, first in enumerate(group) for second in group[i + 1:]]


def _finite(values: np.ndarray) -> np.ndarray:
    """The values of episodes that reached the checkpoint (turn axis: every episode does)."""
    return values[np.isfinite(values)]
