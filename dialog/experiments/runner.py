"""Run a suite's episodes on local cores or on a Ray cluster, with a progress line (``progress.py``)."""

from __future__ import annotations

import os
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import replace
from pathlib import Path

from dialog.experiments.episodes import EpisodeSpec, run_episode
from dialog.experiments.progress import Progress, SweepProgress
from dialog.experiments.suite import Suite
from learning.actions import DEFAULT_COSTS
from learning.errors import SetupError
from learning.strategies import file_label


def episode_specs(suite: Suite, results_dir: Path) -> list[EpisodeSpec]:
    """Every (condition, strategy, data set, seed) of the suite, in a stable order."""
    specs = []
    costs = tuple(sorted((suite.costs or DEFAULT_COSTS).items()))  # no [costs] table: the thesis's costs
    for condition in suite.conditions:
        for strategy in suite.strategies:
            for dataset in range(suite.datasets):
                for seed in suite.seeds:
                    transcript = (results_dir / "transcripts" / condition.name
                                  / f"{file_label(strategy)}-d{dataset}-s{seed}.jsonl")
                    specs.append(EpisodeSpec(
                        suite=suite.name, task=suite.task, kitchen=suite.kitchen, strategy=strategy,
                        condition=condition, dataset=dataset, seed=seed, costs=costs,
                        teacher=tuple(sorted((suite.teacher | dict(condition.teacher)).items())),
                        transcript=str(transcript),
                        plan=suite.plan_options, data_seed=suite.data_seed, weights=suite.weights.get(strategy)))
    return specs


ProgressOption = bool | Progress  # True: a line of its own; False: none; a Progress: a line shared with a longer run


def run_locally(specs: list[EpisodeSpec], workers: int | None = None,
                progress: ProgressOption = True) -> list[dict]:
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


class EpisodePool:
    """One pool of worker processes for several runs of episodes (``regress --data-seeds``: every data seed of a
    suite), so that workers start once and the next data seed's episodes run while the last one's report is
    written. ``submit`` starts episodes early; ``results`` returns a run's results in the order of its specs,
    as ``run_locally`` does (each episode is the same pure function of its spec, wherever it runs)."""

    def __init__(self, workers: int):
        self.workers = workers
        self._executor = ProcessPoolExecutor(max_workers=workers)
        self._futures: dict[str, Future] = {}  # by transcript path: one per episode of a run

    def submit(self, specs: list[EpisodeSpec]) -> None:
        for spec in specs:
            if spec.transcript not in self._futures:
                self._futures[spec.transcript] = self._executor.submit(run_episode, spec)

    def results(self, specs: list[EpisodeSpec], progress: ProgressOption = True) -> list[dict]:
        self.submit(specs)  # any not started yet
        futures = {self._futures.pop(spec.transcript): i for i, spec in enumerate(specs)}
        results: list[dict | None] = [None] * len(specs)
        with _progress(len(specs), progress) as advance:
            for future in as_completed(futures):
                index = futures[future]
                results[index] = future.result()
                advance(specs[index].label)
        return results

    def __enter__(self) -> EpisodePool:
        return self

    def __exit__(self, kind, *exc) -> None:
        self._executor.shutdown(wait=True, cancel_futures=kind is not None)


def run_on_ray(specs: list[EpisodeSpec], address: str, progress: ProgressOption = True) -> list[dict]:
    """Run the same episodes as Ray tasks on the cluster at ``address`` ("local" starts one here); each
    transcript comes back with its result and is written here, wherever the episode ran."""
    ray = connect_ray(address)
    remote_episode = ray.remote(episode_on_node)
    pending = {remote_episode.remote(spec): i for i, spec in enumerate(specs)}
    results: list[dict | None] = [None] * len(specs)
    with _progress(len(specs), progress) as advance:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            index = pending.pop(done[0])
            results[index], transcript = ray.get(done[0])
            path = Path(specs[index].transcript)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(transcript)
            advance(specs[index].label)
    return results


def episode_on_node(spec: EpisodeSpec) -> tuple[dict, bytes]:
    """One episode on a cluster node: its transcript is written in the node's temporary folder (the driver's
    results folder may not exist there) and sent back as bytes with the result."""
    with tempfile.TemporaryDirectory(prefix="teachbot-episode-") as folder:
        here = replace(spec, transcript=str(Path(folder) / Path(spec.transcript).name))
        result = run_episode(here)
        transcript = Path(here.transcript).read_bytes()
    result["spec"]["transcript"] = spec.transcript
    return result, transcript


def connect_ray(address: str, command: str = "regress"):
    """The ``ray`` module, connected to the cluster at ``address`` ("local": a one-node instance started here).

    Ray is optional: without it a one-line SetupError says how to install it."""
    try:
        import ray
    except ImportError:
        raise SetupError("--ray needs the optional extra: pip install 'teachbot[ray]'") from None
    if address == "local":
        start_local_ray(ray)
    else:
        print(f"teachbot {command}: --ray {address}: this code runs on that cluster and its results are unpickled "
              "here; name only a cluster you trust", file=sys.stderr)
        ray.init(address=address, ignore_reinit_error=True, log_to_driver=False)
    return ray


LOCAL_RAY_ENVIRONMENT = {
    "RAY_AUTH_MODE": "token",  # every Ray RPC carries the cluster's token (Ray writes it to ~/.ray/auth_token)
    "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0",  # a one-node instance: Ray binds its servers to 127.0.0.1
}


def start_local_ray(ray) -> None:
    """Start a one-node Ray instance here, bound to 127.0.0.1, with token authentication, no dashboard.

    Ray picks the loopback address when clusters are turned off (``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0``,
    read at import and by the processes it starts). Token mode stays set: this process talks to the
    instance with it. ``ray.init`` replaces the SIGTERM handler; it is put back so SIGTERM still ends
    ``teachbot`` cleanly.
    """
    if ray.is_initialized():
        return
    mode = os.environ.get("RAY_AUTH_MODE", "token")
    if mode.lower() != "token":
        print(f"teachbot regress: RAY_AUTH_MODE={mode} ignored: --ray local always uses token authentication",
              file=sys.stderr)
    constants = ray._private.ray_constants
    saved_variable = os.environ.get("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER")
    saved_flag, saved_sigterm = constants.ENABLE_RAY_CLUSTER, signal.getsignal(signal.SIGTERM)
    os.environ.update(LOCAL_RAY_ENVIRONMENT)
    constants.ENABLE_RAY_CLUSTER = False  # in case ray was imported before the variable was set
    try:
        _reload_ray_settings(ray)
        ray.init(include_dashboard=False, log_to_driver=False)
        _check_token_mode(ray)
    finally:
        constants.ENABLE_RAY_CLUSTER = saved_flag
        if saved_variable is None:
            del os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"]
        else:
            os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = saved_variable
        if saved_sigterm is not None and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, saved_sigterm)


def _reload_ray_settings(ray) -> None:
    """Make Ray's cached settings (read when ``ray`` was imported) see RAY_AUTH_MODE, as Ray does itself."""
    config = getattr(getattr(ray, "_raylet", None), "Config", None)
    if config is not None:
        config.initialize("")


def _check_token_mode(ray) -> None:
    mode = getattr(getattr(ray, "_raylet", None), "get_authentication_mode", None)
    if mode is None or mode() != ray._raylet.AuthenticationMode.TOKEN:
        ray.shutdown()
        raise SetupError(f"--ray local needs token authentication, which Ray {ray.__version__} does not offer "
                         "(it came in Ray 2.52): pip install 'ray>=2.52'")


class _progress:
    """The progress of ``total`` runs: a run's own line (``enabled`` True), none (False), or a line shared with
    the rest of a longer run (a ``dialog.experiments.progress`` object, which its owner closes)."""

    def __init__(self, total: int, enabled: ProgressOption, what: str = "episodes"):
        self.total, self.enabled, self.what = total, enabled, what
        self._own: SweepProgress | None = None

    def __enter__(self) -> Callable[[str], None]:
        if self.enabled is False:
            return lambda label: None
        shared = self.enabled if not isinstance(self.enabled, bool) else None
        if shared is None:
            self._own = shared = SweepProgress(self.total, self.what)
        return lambda label: shared.advance()

    def __exit__(self, *exc) -> None:
        if self._own is not None:
            self._own.close()


class RenderBar:
    """A progress bar on standard error while data sets are rendered on a first run, with the time so far.

    Use as ``with RenderBar("pack-lunchbox/kitchen-1") as bar: load_pools(..., progress=bar)``: the
    bar appears with the first pool rendered and shows nothing when the pools come from the cache.
    """

    def __init__(self, what: str, enabled: bool = True):
        self.what, self.enabled = what, enabled
        self._bar = self._task = None

    def __enter__(self) -> RenderBar:
        self._started = time.perf_counter()
        return self

    def __call__(self, done: int, total: int, message: str) -> None:
        if not self.enabled:
            return
        if self._bar is None:
            self._start(total)
        self._bar.update(self._task, completed=done, description=message.split(": ", 1)[-1])

    def _start(self, total: int) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TextColumn
        from rich.text import Text

        started = self._started

        class SinceStart(ProgressColumn):
            """Minutes:seconds since the rendering began (before the first pool was done)."""

            def render(self, task) -> Text:
                seconds = int(time.perf_counter() - started)
                return Text(f"{seconds // 60}:{seconds % 60:02d}", style="progress.elapsed")

        console = Console(file=sys.stderr)
        self._bar = Progress(TextColumn(f"rendering the data sets of {self.what} (first run; cached afterwards)"),
                             BarColumn(), MofNCompleteColumn(), SinceStart(), TextColumn("{task.description}"),
                             console=console, transient=not console.is_terminal)
        self._bar.start()
        self._task = self._bar.add_task("", total=total)

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.stop()
            seconds = time.perf_counter() - self._started
            print(f"rendered the data sets of {self.what} in {seconds:.0f} s; cached for the next runs",
                  file=sys.stderr)
