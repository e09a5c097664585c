"""From episode results to numbers: accuracy at checkpoints, summaries, finding tests."""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from dialog.experiments.suite import Finding, Suite
from learning.significance import Comparison, accuracy_after_questions, mann_whitney, mean_and_standard_error


def checkpoint_values(result: dict, suite: Suite) -> np.ndarray:
    """One episode's accuracy at each of the suite's checkpoints (questions asked, or turns).

    An episode that never asked as many questions as a checkpoint (its strategy
    chose to stay quiet, or its time ran out) counts with its final accuracy:
    that is what it learned with what it chose to ask.
    """
    series = result["series"]
    accuracy = np.asarray(series["accuracy"], dtype=float)
    if suite.axis == "questions":
        values = accuracy_after_questions(np.asarray(series["questions"]), accuracy, suite.checkpoints)
        return np.where(np.isnan(values), accuracy[-1], values)
    turns = np.asarray(series["turn"])
    return np.array([accuracy[turns <= t][-1] if np.any(turns <= t) else np.nan for t in suite.checkpoints])


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


def summarise(results: list[dict], suite: Suite) -> list[CheckpointSummary]:
    summaries = []
    for (condition, strategy), group in group_results(results).items():
        values = np.vstack([checkpoint_values(r, suite) for r in group])
        mean, error = mean_and_standard_error(values)
        summaries.append(CheckpointSummary(condition, strategy, suite.checkpoints, mean, error, values))
    return summaries


@dataclass(frozen=True)
class FindingResult:
    finding: Finding
    comparisons: tuple[Comparison, ...]

    @property
    def holds(self) -> bool:
        return bool(self.comparisons) and all(c.significant for c in self.comparisons)


def evaluate_findings(summaries: list[CheckpointSummary], suite: Suite) -> list[FindingResult]:
    """One-tailed (or as the suite says) Mann-Whitney tests of each finding at its checkpoint."""
    lookup = {(s.condition, s.strategy): s for s in summaries}
    outcomes = []
    for finding in suite.findings:
        if finding.at not in suite.checkpoints:
            raise ValueError(f"finding '{finding.id}' is checked at {finding.at}, which is not a checkpoint "
                             f"of suite '{suite.name}' {list(suite.checkpoints)}")
        better_summary = lookup[(finding.condition, finding.better)]
        column = better_summary.checkpoints.index(finding.at)
        better = better_summary.values[:, column]
        comparisons = []
        for other in finding.than:
            values = lookup[(finding.condition, other)].values[:, column]
            comparisons.append(mann_whitney(finding.better, _finite(better), other, _finite(values),
                                            finding.alternative))
        outcomes.append(FindingResult(finding, tuple(comparisons)))
    return outcomes


def pairwise(summaries: list[CheckpointSummary], condition: str, column: int) -> list[Comparison]:
    """Two-sided Mann-Whitney between every pair of strategies in one condition at one checkpoint."""
    group = [s for s in summaries if s.condition == condition]
    comparisons = []
    for i, first in enumerate(group):
        for second in group[i + 1:]:
            comparisons.append(mann_whitney(first.strategy, _finite(first.values[:, column]), second.strategy,
                                            _finite(second.values[:, column])))
    return comparisons


def _finite(values: np.ndarray) -> np.ndarray:
    """The values of episodes that reached the checkpoint (turn axis: every episode does)."""
    return values[np.isfinite(values)]
