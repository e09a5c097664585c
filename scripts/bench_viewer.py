"""What the meshcat viewer costs an episode: the same seeded episode with and without it, in one run.

Conditions, interleaved over ``--reps`` rounds (median wall time of each):

- ``headless``: no viewer (the reference);
- ``live``: the live viewer (loopback server, meshcat thread, frames after steps and events);
- ``live+browser``: the live viewer with headless Chromium showing the page (when chromium and
  playwright are installed; the browser renders on the same CPUs);
- ``export``: no live server, the episode recorded and written as one static HTML page.

Every condition runs the whole session a user waits for: the kitchen and arm are built, the
viewer started, the episode played (``DialogManager`` with the oracle teacher), the viewer
closed (and the page written). The goal is a slowdown of at most 20 % for ``live``.

    python scripts/bench_viewer.py --turns 30 --reps 3 --json
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bullet_world.viewer.mirror import Viewer
from bullet_world.viewer.snapshot import CHROMIUM_FLAGS, COUNT_DRAWN_JS, find_chromium
from dialog.environment import SimulatedKitchen
from dialog.episode import build_episode
from dialog.manager import episode_generators
from dialog.settings import EpisodeSettings
from dialog.teachers.scripted import OracleTeacher
from dialog.transcripts.jsonl import TranscriptWriter

GOAL = 0.20
SETTLE_S = 1.0  # pause after each session, so that one session's leftovers don't slow the next


class Browser:
    """Headless Chromium kept open on a page while an episode runs (None when unavailable)."""

    def __init__(self):
        from playwright.sync_api import sync_playwright

        self._profile = tempfile.TemporaryDirectory(prefix="bench-viewer-chromium-")
        self._driver = sync_playwright().start()
        self._context = self._driver.chromium.launch_persistent_context(
            self._profile.name, executable_path=find_chromium(), headless=True, args=list(CHROMIUM_FLAGS),
            viewport={"width": 1024, "height": 700})
        self.page = self._context.new_page()

    def show(self, url: str, min_drawn: int, timeout_s: float = 60.0) -> None:
        self.page.goto(url, wait_until="load")
        deadline = time.perf_counter() + timeout_s
        while self.page.evaluate(COUNT_DRAWN_JS) < min_drawn:
            if time.perf_counter() > deadline:
                raise RuntimeError("the browser never drew the scene")
            self.page.wait_for_timeout(200)

    def close(self) -> None:
        self._context.close()
        self._driver.stop()
        self._profile.cleanup()


def episode(condition: str, args, folder: Path) -> dict:
    """One session; returns wall seconds (whole session and the episode alone), this process's CPU seconds
    (all its threads; not the server's or the browser's) and viewer figures. The browser is started
    before the clock and closed after it, so that it burns no CPU during the other conditions."""
    browser = Browser() if condition == "live+browser" else None
    started, cpu_started = time.perf_counter(), time.process_time()
    environment = SimulatedKitchen(task=args.task, kitchen=args.kitchen, seed=args.seed)
    viewer = None
    figures: dict = {}
    try:
        if condition != "headless":
            viewer = Viewer(environment.world, live=condition != "export",
                            export_path=folder / f"episode-{condition}.html" if condition == "export" else None)
            if browser is not None:
                browser.show(viewer.url, min_drawn=10)
        rngs = episode_generators(args.seed)
        settings = EpisodeSettings(task=args.task, kitchen=args.kitchen, strategy=args.strategy, seed=args.seed,
                                   turns=args.turns, budget=args.budget, change_every=args.change_every)
        with TranscriptWriter(folder / f"{condition}.jsonl") as transcript:
            manager = build_episode(settings, environment, OracleTeacher(rngs["teacher"]), transcript, rngs=rngs,
                                    say=lambda *_: None, observers=(viewer,) if viewer is not None else ())
            episode_started = time.perf_counter()
            result = manager.run()
            episode_seconds = time.perf_counter() - episode_started
        if viewer is not None:
            closing = time.perf_counter()
            written = viewer.close()
            figures = {"close_seconds": time.perf_counter() - closing,
                       "frames_published": viewer.thread.frames_published,
                       "frames_applied": viewer.thread.frames_applied}
            if viewer.thread.scene is not None:
                figures["sent"] = dict(viewer.thread.scene.sent)
            if written:
                figures.update(page_bytes=written["bytes"], animation_seconds=written["seconds"],
                               recorded_samples=viewer.recording.samples)
    finally:
        if viewer is not None:
            viewer.close()
        environment.close()
    seconds, cpu_seconds = time.perf_counter() - started, time.process_time() - cpu_started
    if browser is not None:
        browser.close()
    time.sleep(SETTLE_S)
    return {"seconds": seconds, "episode_seconds": episode_seconds, "cpu_seconds": cpu_seconds,
            "accuracy": result.accuracy, **figures}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--turns", type=int, default=30)
    parser.add_argument("--budget", type=float, default=40.0)
    parser.add_argument("--change-every", type=int, default=5)
    parser.add_argument("--strategy", default="active")
    parser.add_argument("--task", default="pack-lunchbox")
    parser.add_argument("--kitchen", default="kitchen-1")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--reps", type=int, default=3, help="rounds; each runs every condition once (default 3)")
    parser.add_argument("--no-browser", action="store_true", help="skip the live+browser condition")
    parser.add_argument("--json", action="store_true", help="end with one JSON line of the figures")
    args = parser.parse_args(argv)
    if args.turns < 1 or args.reps < 1:
        parser.error("--turns and --reps must be at least 1")

    conditions = ["headless", "live", "export"]
    if not args.no_browser and find_chromium() is not None:
        try:
            Browser().close()
            conditions.insert(2, "live+browser")
        except Exception as error:  # the other conditions still mean something
            print(f"live+browser skipped: {type(error).__name__}: {error}", file=sys.stderr)
    runs: dict[str, list[dict]] = {c: [] for c in conditions}
    with tempfile.TemporaryDirectory(prefix="bench-viewer-") as folder:
        for rep in range(args.reps):  # the order rotates, so a machine getting busier favours nobody
            for condition in conditions[rep % len(conditions):] + conditions[:rep % len(conditions)]:
                run = episode(condition, args, Path(folder))
                runs[condition].append(run)
                print(f"round {rep + 1} {condition:<13} session {run['seconds']:6.2f} s   "
                      f"episode {run['episode_seconds']:6.2f} s   cpu {run['cpu_seconds']:6.2f} s", file=sys.stderr)

    reference = statistics.median(r["seconds"] for r in runs["headless"])
    reference_episode = statistics.median(r["episode_seconds"] for r in runs["headless"])
    reference_cpu = statistics.median(r["cpu_seconds"] for r in runs["headless"])
    summary = {"turns": args.turns, "seed": args.seed, "reps": args.reps, "goal_slowdown": GOAL, "conditions": {}}
    print(f"\n{args.turns}-turn episode, seed {args.seed}, median of {args.reps} (wall seconds):")
    print(f"{'condition':<14}{'session':>9}{'episode':>9}{'slowdown':>10}{'cpu':>8}{'cpu +':>8}   notes")
    for condition, results in runs.items():
        seconds = statistics.median(r["seconds"] for r in results)
        episode_seconds = statistics.median(r["episode_seconds"] for r in results)
        cpu = statistics.median(r["cpu_seconds"] for r in results)
        slowdown = seconds / reference - 1.0
        last = results[-1]
        notes = {key: last[key] for key in ("frames_published", "frames_applied", "sent", "page_bytes",
                                             "animation_seconds", "recorded_samples", "close_seconds") if key in last}
        summary["conditions"][condition] = {
            "session_seconds": round(seconds, 3), "episode_seconds": round(episode_seconds, 3),
            "slowdown": round(slowdown, 4), "episode_slowdown": round(episode_seconds / reference_episode - 1.0, 4),
            "cpu_seconds": round(cpu, 3), "cpu_increase": round(cpu / reference_cpu - 1.0, 4),
            "all_session_seconds": [round(r["seconds"], 3) for r in results], **notes}
        text = ", ".join(f"{k}={v if not isinstance(v, float) else round(v, 2)}" for k, v in notes.items())
        print(f"{condition:<14}{seconds:>9.2f}{episode_seconds:>9.2f}{slowdown:>+10.1%}{cpu:>8.2f}"
              f"{cpu / reference_cpu - 1.0:>+8.1%}   {text}")
    live = summary["conditions"]["live"]["slowdown"]
    summary["live_within_goal"] = bool(live <= GOAL)
    print(f"\nlive viewer slowdown {live:+.1%} (goal <= {GOAL:.0%}): {'met' if live <= GOAL else 'NOT met'}")
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
