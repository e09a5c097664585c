"""Run a suite's episodes on local cores (with a progress bar) or on a Ray cluster."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from dialog.regress.episodes import EpisodeSpec, run_episode
from dialog.regress.suite import Suite


def episode_specs(suite: Suite, results_dir: Path) -> list[EpisodeSpec]:
    """Every (condition, strategy, data set, seed) of the suite, in a stable order."""
    specs = []
    for condition in suite.conditions:
        for strategy in suite.strategies:
            for dataset in range(suite.datasets):
                for seed in suite.seeds:
                    transcript = results_dir / "transcripts" / condition.name / f"{strategy}-d{dataset}-s{seed}.jsonl"
                    specs.append(EpisodeSpec(
                        suite=suite.name, task=suite.task, kitchen=suite.kitchen, strategy=strategy,
                        condition=condition, dataset=dataset, seed=seed, costs=tuple(sorted(suite.costs.items())),
                        teacher=tuple(sorted(suite.teacher.items())), transcript=str(transcript),
                        plan=suite.plan_options))
    return specs


def run_locally(specs: list[EpisodeSpec], workers: int | None = None, progress: bool = True) -> list[dict]:
    """Run episodes in worker processes; results come back in the order of ``specs``."""
    workers = max(1, min(workers or os.cpu_count() or 1, len(specs)))
    results: list[dict | None] = [None] * len(specs)
    with _progress(len(specs), progress) as advance:
        if workers == 1:
            for index, spec in enumerate(specs):
                results[index] = run_episode(spec)
                advance(spec.label)
        else:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futures = {pool.submit(run_episode, spec): i for i, spec in enumerate(specs)}
                for future in as_completed(futures):
                    index = futures[future]
                    results[index] = future.result()
                    advance(specs[index].label)
    return results


def run_on_ray(specs: list[EpisodeSpec], address: str, progress: bool = True) -> list[dict]:
    """Run the same episodes as Ray tasks on the cluster at ``address`` ("local" starts one here)."""
    try:
        import ray
    except ImportError:
        raise RuntimeError("--ray needs the optional extra: pip install 'teachbot[ray]'") from None
    ray.init(address=None if address == "local" else address, include_dashboard=False,
             ignore_reinit_error=True, log_to_driver=False)
    remote_episode = ray.remote(run_episode)
    pending = {remote_episode.remote(spec): i for i, spec in enumerate(specs)}
    results: list[dict | None] = [None] * len(specs)
    with _progress(len(specs), progress) as advance:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            index = pending.pop(done[0])
            results[index] = ray.get(done[0])
            advance(specs[index].label)
    return results


class _progress:
    """A rich progress bar on standard error (kept off standard output, which may carry JSON)."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.enabled = total, enabled

    def __enter__(self) -> Callable[[str], None]:
        if not self.enabled:
            return lambda label: None
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        console = Console(file=sys.stderr)
        self._bar = Progress(TextColumn("episodes"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                             TextColumn("{task.description}"), console=console, transient=not console.is_terminal)
        self._bar.start()
        task = self._bar.add_task("", total=self.total)
        return lambda label: self._bar.update(task, advance=1, description=label)

    def __exit__(self, *exc) -> None:
        if self.enabled:
            self._bar.stop()
