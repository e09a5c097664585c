"""Suite kinds behind one small interface, registered by name.

A suite file's ``kind`` picks one of the registered kinds; ``teachbot regress``
asks the registry for it and calls the same four steps on every kind:

    kind = get_kind(suite.kind)
    suite = kind.load(suite)                  # the kind's own checks, before anything runs
    run = kind.run(suite, RunOptions(...))    # results, summaries at checkpoints, finding tests
    paths = kind.report(run, folder)          # report.md first, then CSV files and figures
    problems = kind.check(run, baseline)      # readable differences from the stored baseline

The built-in kinds (episodes, feature-selection, recipes) register when first
asked for; another kind registers with ``dialog.experiments.registry.register_kind``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from dialog.experiments.analysis import CheckpointSummary, FindingResult, skipped_by_overrides
from dialog.experiments.baseline import BaselineFailures, check_against_baseline
from dialog.experiments.progress import Progress
from dialog.experiments.registry import kind_names, registered
from dialog.experiments.suite import Suite, SuiteError


@dataclass(frozen=True)
class RunOptions:
    """How to run a suite: where its files go, worker processes, a Ray cluster, progress shown.

    ``progress``: bars and lines at all (rendering the data sets, the episodes); ``sweep``: the progress line
    the episodes advance when it is shared with a longer run (``dialog.experiments.progress``; None: the
    suite's own line)."""

    results: Path
    workers: int | None = None
    ray: str | None = None
    progress: bool = True
    sweep: Progress | None = None
    pool: Any = None  # a dialog.experiments.runner.EpisodePool shared by several runs (None: the run's own)


@dataclass(frozen=True)
class SweepUse:
    """How a sweep used the machine: its runs, their wall time together, the CPU time they spent, the cores.

    ``cpu_use`` is the runs' own CPU time (measured inside each, wherever it ran) over wall time x cores:
    1.0 keeps every core busy with the runs; process start-up and result passing count as idle.
    """

    runs: int
    seconds: float
    cpu_seconds: float
    cores: int

    @property
    def runs_per_second(self) -> float:
        return self.runs / self.seconds if self.seconds > 0 else 0.0

    @property
    def cpu_use(self) -> float:
        return self.cpu_seconds / (self.seconds * self.cores) if self.seconds > 0 else 0.0

    def line(self, what: str = "episodes") -> str:
        return (f"{self.runs} {what} in {self.seconds:.1f} s: {self.runs_per_second:.2f} {what} per second; "
                f"CPU use {self.cpu_use:.0%} of {self.cores} cores")


@dataclass
class SuiteRun:
    """What one run of a suite produced; ``data`` is the kind's own results (episodes, rows, trials)."""

    suite: Suite
    data: Any
    summaries: list[CheckpointSummary]
    findings: list[FindingResult]
    count: int
    seconds: float
    extra: dict = field(default_factory=dict)  # kind-specific context the report needs (e.g. a recipe study)


class SuiteKind(ABC):
    """One kind of suite: load (check), run, report, check against a baseline."""

    name: ClassVar[str]

    def load(self, suite: Suite) -> Suite:
        """Check what only this kind knows about the suite; raise ``SuiteError`` naming the file."""
        return suite

    @abstractmethod
    def run(self, suite: Suite, options: RunOptions) -> SuiteRun:
        """Run every trial of the suite; summaries and finding tests included."""

    @abstractmethod
    def report(self, run: SuiteRun, folder: Path) -> list[Path]:
        """Write the report (first path), its tables and figures into ``folder``."""

    def check(self, run: SuiteRun, baseline: Path | None = None) -> BaselineFailures:
        """Readable differences from the stored baseline bands (empty: every mean is inside)."""
        return check_against_baseline(run.suite, run.summaries, baseline)


def get_kind(name: str) -> SuiteKind:
    """The registered kind called ``name``; an unknown name is one message listing the registered kinds."""
    names = kind_names()
    kinds = registered()
    if name not in kinds:
        raise SuiteError(f"unknown suite kind '{name}'; registered kinds: {', '.join(names)}")
    kind = kinds[name]
    if not isinstance(kind, SuiteKind):
        raise TypeError(f"the suite kind registered as '{name}' ({type(kind).__name__}) is not a SuiteKind "
                        "subclass (dialog.experiments.kinds.SuiteKind)")
    return kind


def run_suite(kind: SuiteKind, suite: Suite, options: RunOptions, original: Suite | None = None) -> SuiteRun:
    """Run ``suite`` with ``kind``; findings of ``original`` that a strategy subset left out come back skipped."""
    run = kind.run(suite, options)
    if original is not None:
        order = {finding.id: index for index, finding in enumerate(original.findings)}
        run.findings = sorted([*run.findings, *skipped_by_overrides(original, suite)],
                              key=lambda outcome: order.get(outcome.finding.id, len(order)))
    return run
