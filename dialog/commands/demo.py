"""``teachbot demo``: one scripted teaching episode in the simulated kitchen."""

from __future__ import annotations

import argparse
from dataclasses import asdict
from pathlib import Path

from dialog.commands._arguments import add_episode_options, add_time_options, resolve_time
from dialog.commands._arguments import seconds as seconds_type
from dialog.commands._json import print_json
from dialog.commands._summary import questions_in_words, scene_size
from dialog.environment import SimulatedKitchen
from dialog.episode import build_episode, embodied_timing
from dialog.experiments.runner import file_label
from dialog.manager import episode_generators
from dialog.output_paths import file_argument, numbered
from dialog.settings import DEFAULTS, EpisodeSettings
from dialog.teachers.scripted import OracleTeacher
from dialog.transcripts.jsonl import TranscriptWriter, refuse_foreign_transcript
from dialog.transcripts.lock import TranscriptLock
from dialog.user_weights import WEIGHTS_STRATEGY_NAME, add_weights_option, weights_strategy
from dialog.viewer import DEFAULT_PACE_S, Pacer, add_viewer_option, hold_viewer, pace_of, viewer_observers
from dialog.web.session import add_web_options, check_web_options
from learning.strategies import DEFAULT_STRATEGY, STRATEGY_NAMES

SUMMARY_KEYS = ("seed", "strategy", "turns", "budget_spent", "queries", "accuracy", "transcript", "seconds")


def register(commands) -> None:
    parser = commands.add_parser(
        "demo", help="run one scripted teaching episode in the simulated kitchen",
        description="A scripted teacher (an oracle) answers the robot's questions for one episode in the simulated "
                    "kitchen; the summary gives the accuracy on held-out scenes, the budget spent and the questions "
                    "asked. Every turn goes to a transcript (JSON Lines); the same seed gives the same transcript.")
    add_episode_options(parser, STRATEGY_NAMES, DEFAULT_STRATEGY)
    add_time_options(parser)
    parser.add_argument("--transcript", type=file_argument, default=None,
                        help="transcript path (default runs/demo-<strategy>-seed<seed>.jsonl; a non-default "
                             "task, kitchen or --embodied-costs adds itself to the name)")
    add_weights_option(parser)
    add_viewer_option(parser)
    parser.add_argument("--pace", type=seconds_type, default=None, metavar="SECONDS",
                        help=f"each turn lasts at least SECONDS of wall time, so a person can follow (default "
                             f"{DEFAULT_PACE_S:g} with --viewer or --web, else 0); the transcript is the same")
    add_web_options(parser, "watch the episode turn by turn")
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the episode")
    parser.set_defaults(handler=run)


def default_transcript(args: argparse.Namespace, seconds: float | None) -> Path:
    """runs/demo-<strategy>[-<task>][-<kitchen>][-embodied-<N>s]-seed<seed>.jsonl: the parts that differ from the
    defaults name the file, so an embodied demo does not overwrite the plain demo's transcript; numbered (-2, -3,
    ...) as teach's when taken, so no earlier demo is overwritten."""
    parts = [file_label(args.strategy)]
    parts += [value for value, default in ((args.task, DEFAULTS.task), (args.kitchen, DEFAULTS.kitchen))
              if value != default]
    if seconds is not None:
        parts.append(f"embodied-{seconds:g}s")
    return numbered(Path("runs") / f"demo-{'-'.join(parts)}-seed{args.seed}.jsonl")


def run(args: argparse.Namespace) -> int:
    check_web_options(args)
    turns, seconds = resolve_time(args)
    args.strategy, weights = weights_strategy(args.strategy, args.weights)  # --weights: DT shown as "dt"
    session = {"command": "demo"} if weights is None else {"command": "demo", "weights": weights.record()}
    if weights is not None:
        print(f"Strategy {WEIGHTS_STRATEGY_NAME}: DT with the weights in {weights.describe()}", flush=True)
    settings = EpisodeSettings(task=args.task, kitchen=args.kitchen, strategy=args.strategy, seed=args.seed,
                               turns=turns, budget=args.budget, change_every=args.change_every, seconds=seconds,
                               weights=None if weights is None else weights.record())
    strategy = settings.build_strategy()  # before anything is opened: a strategy that can't be built is one line
    timing = embodied_timing(seconds)
    rngs = episode_generators(args.seed)
    transcript_path = args.transcript or default_transcript(args, seconds)
    lock = TranscriptLock(transcript_path)  # checked and held before the kitchen is built: one writer per file
    try:
        refuse_foreign_transcript(transcript_path, lock, "demo")
        environment = SimulatedKitchen(task=args.task, kitchen=args.kitchen, seed=args.seed,
                                       joint_speed=timing.joint_speed)
        pace = pace_of(args)
        try:
            if args.web:
                _watch_in_page(args, environment, pace, lambda observers: _episode(
                    args, environment, settings, strategy, transcript_path, lock, rngs, timing,
                    session, observers))
            else:
                with viewer_observers(args, environment.world) as observers:
                    _episode(args, environment, settings, strategy, transcript_path, lock, rngs, timing,
                             session, ((Pacer(pace),) if pace > 0 else ()) + observers)
                    hold_viewer(args, observers[0] if observers else None)
        finally:
            environment.close()
    finally:
        lock.release()
    return 0


def _episode(args, environment, settings, strategy, transcript_path, lock, rngs, timing, session, observers):
    with TranscriptWriter(transcript_path, lock=lock) as transcript:
        teacher = OracleTeacher(rngs["teacher"], clock=timing.clock, answer_delays=timing.answer_delays)
        manager = build_episode(settings, environment, teacher, transcript, strategy=strategy, rngs=rngs,
                                observers=observers, session=session, clock=timing.clock)
        result = manager.run()
    return _print_summary(args, result, environment, manager)


def _watch_in_page(args, environment, pace: float, play) -> None:
    """``demo --web``: the page shows the scripted episode as it happens, once a browser has opened it."""
    from dialog.web.session import WebPage

    page = WebPage.for_session(args, environment, title="teachbot demo")
    try:
        page.wait_for_viewer_page()
        summary = play((*((Pacer(pace),) if pace > 0 else ()), *page.observers, page.watcher()))
        page.teacher.end(summary)
    finally:
        page.close()


def _print_summary(args: argparse.Namespace, result, environment, manager) -> None:
    score, when, used = result.accuracy, "", ""
    if manager.embodied is not None:  # scored at the allocation's end: a turn that ends past it does not count
        allocation = manager.config.seconds
        score = result.allocation_accuracy
        when = f" after {allocation:g} s (turn {result.allocation_turns}, the last that ended within them)"
        if score is None:
            score, when = float("nan"), f" after {allocation:g} s (no turn ended within them)"
        used = f"time used {manager.clock.now():.0f} of {allocation:g} s in {result.completed} turns; "
    shown = "none" if score != score else f"{score:.1%}"
    line = (f"Accuracy on {args.task} held-out scenes{when}: {shown} "
            f"(chance {1 / len(environment.concepts):.0%}); budget spent {result.budget_spent:g} of {args.budget:g}; "
            f"questions: {questions_in_words(result.queries)}; {scene_size(environment.world.task)}; "
            f"{used}{result.seconds:.1f} s. "
            f"Transcript: {result.transcript}")
    print(f"\n{line}", flush=True)
    if args.json:
        summary = {key: asdict(result)[key] for key in SUMMARY_KEYS} | {"accuracy": score}
        summary["queries"] = {kind: summary["queries"][kind] for kind in ("label", "demo", "feature", "none")}
        print_json(summary)
    return line
