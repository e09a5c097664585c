"""``teachbot teach``: teach the robot at the terminal (or let a scripted teacher do it), resumable."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dialog.commands._arguments import (
    TeachbotParser,
    add_episode_options,
    add_time_options,
    budget,
    number_within,
    positive_seconds,
    resolve_time,
)
from dialog.commands._json import print_json
from dialog.commands._resume import UNRECORDED_TEACH_OPTIONS, check_resume_options, continue_command
from dialog.commands._summary import questions_in_words, scene_size, session_time
from dialog.environment import SimulatedKitchen
from dialog.episode import embodied_timing
from dialog.experiments.runner import file_label
from dialog.output_paths import check_writable, file_argument, numbered
from dialog.session import TEACHERS, SessionSettings, open_session
from dialog.transcripts.jsonl import read_session
from dialog.transcripts.lock import TranscriptLock
from dialog.user_weights import add_weights_option, weights_strategy
from dialog.viewer import add_viewer_option, hold_viewer, start_viewer, stop_viewer
from dialog.web import words
from dialog.web.session import add_web_options, check_web_options, web_continue_options
from learning.errors import OutputPathError, SettingsError, TranscriptError
from learning.strategies import DEFAULT_STRATEGY, STRATEGY_NAMES

rate = number_within(float, 0.0, 1.0, "a number between 0 and 1")


def register(commands) -> None:
    parser = commands.add_parser(
        "teach", help="teach the robot at the terminal: it points, asks, and learns from your answers",
        description="Answer the robot's questions at the terminal. Type 'help' at any question for the accepted "
                    "answers; 'quit' (or end of input) saves the session, which --resume continues.")
    add_episode_options(parser, STRATEGY_NAMES, DEFAULT_STRATEGY)
    add_time_options(parser)
    parser.add_argument("--realtime", type=positive_seconds, default=None, metavar="SECONDS",
                        help="real-time mode: each turn lasts SECONDS; a later answer counts as none")
    parser.add_argument("--transcript", type=file_argument, default=None,
                        help="transcript path (default runs/teach-<task>-<strategy>-seed<seed>.jsonl, numbered "
                             "if taken)")
    parser.add_argument("--resume", type=Path, default=None, metavar="FILE",
                        help="continue the session recorded in FILE with its own settings")
    parser.add_argument("--teacher", choices=TEACHERS, default=SessionSettings().teacher["kind"],
                        help="who answers: you (terminal, default), a scripted oracle, or a recorded transcript")
    parser.add_argument("--replay", type=Path, default=None, metavar="FILE",
                        help="the transcript a replay teacher answers from")
    parser.add_argument("--mislabel-rate", type=rate, default=0.0, help="scripted teacher: chance of a wrong label")
    parser.add_argument("--dont-know-rate", type=rate, default=0.0,
                        help="scripted teacher: chance of answering 'I don't know'")
    parser.add_argument("--feature-quality", type=rate, default=1.0,
                        help="scripted teacher: share of the relevant features named (1 = all, no noise)")
    parser.add_argument("--answer-delay", type=budget, default=0.0, metavar="SECONDS",
                        help="scripted teacher: mean seconds per answer")
    parser.add_argument("--pictures", type=Path, default=None, metavar="DIR",
                        help="folder for numbered scene pictures (default: next to the transcript for a person, "
                             "none for a scripted teacher)")
    parser.add_argument("--no-pictures", action="store_true", help="write no scene pictures")
    parser.add_argument("--no-fetch", action="store_true",
                        help="never fetch an absent example from the pantry")
    add_weights_option(parser)
    add_viewer_option(parser)
    add_web_options(parser)
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the session")
    parser.set_defaults(handler=run)


def teach_defaults() -> argparse.Namespace:
    """What ``teachbot teach`` parses when no option is given."""
    commands = TeachbotParser().add_subparsers()
    register(commands)
    return commands.choices["teach"].parse_args([])


def _default_transcript(args, strategy: str) -> Path:
    """runs/teach-<task>-<strategy>-seed<seed>.jsonl, numbered (-2, -3, ...) when taken."""
    return numbered(Path("runs") / f"teach-{args.task}-{file_label(strategy)}-seed{args.seed}.jsonl")


def _settings(args) -> SessionSettings:
    teacher = {"kind": args.teacher}
    if args.teacher == "scripted":
        teacher.update(mislabel_rate=args.mislabel_rate, dont_know_rate=args.dont_know_rate,
                       feature_quality=args.feature_quality, answer_delay=args.answer_delay)
    if args.teacher == "replay":
        if args.replay is None:
            raise SettingsError("--teacher replay needs --replay FILE (a transcript to answer from)")
        teacher["transcript"] = str(args.replay)
    strategy, weights = weights_strategy(args.strategy, args.weights)  # --weights: DT, shown as "dt"
    turns, seconds = resolve_time(args)
    return SessionSettings(task=args.task, kitchen=args.kitchen, strategy=strategy, seed=args.seed,
                           weights=None if weights is None else weights.record(), seconds=seconds,
                           turns=turns, budget=args.budget, change_every=args.change_every,
                           realtime=args.realtime, fetch_from_pantry=not args.no_fetch, teacher=teacher)


def _claim_transcript(args) -> tuple[SessionSettings, Path, TranscriptLock]:
    """The session's settings, its transcript and the transcript's lock, taken before anything is checked."""
    if args.resume is not None:
        if not args.resume.exists():
            raise TranscriptError(f"no transcript at {args.resume} to resume")
        lock = TranscriptLock(args.resume, create=False)
        try:
            header = read_session(args.resume, tolerate_partial_tail=True)[0]
            settings = SessionSettings.from_header(header, args.resume)
            check_resume_options(args, settings, args.resume, teach_defaults())
            return settings, args.resume, lock
        except BaseException:
            lock.release()
            raise
    settings = _settings(args)
    path = args.transcript or _default_transcript(args, settings.strategy)
    lock = TranscriptLock(path)
    if lock.size() > 0:
        lock.release()
        raise TranscriptError(f"{path} already holds a session; continue it with --resume {path} or choose another "
                              "--transcript")
    return settings, path, lock


def _picture_folder(args, path: Path, person: bool) -> Path | None:
    """Where scene pictures go, or None; a folder that can't be written is a warning (pictures are optional)."""
    if args.no_pictures:
        return None
    folder = args.pictures or (path.parent / f"{path.stem}-pictures" if person else None)
    if folder is not None:
        try:
            check_writable(folder, "scene pictures", folder=True)
        except OutputPathError as error:
            print(f"warning: {error}; going on without scene pictures", file=sys.stderr, flush=True)
            return None
    return folder


def run(args: argparse.Namespace, input_stream=None, output_stream=None) -> int:
    check_web_options(args)
    if args.web and args.teacher != "terminal":
        raise SettingsError(f"--web is for a person answering in the page; not with --teacher {args.teacher}")
    settings, path, lock = _claim_transcript(args)
    try:
        return _teach(args, settings, path, lock, input_stream, output_stream)
    finally:
        lock.release()


def _teach(args, settings: SessionSettings, path: Path, lock: TranscriptLock, input_stream, output_stream) -> int:
    person = settings.teacher["kind"] == "terminal"
    pictures = _picture_folder(args, path, person)
    out = output_stream or sys.stdout
    joint_speed = embodied_timing(settings.seconds).joint_speed  # embodied costs: the arm's joint-speed limit
    environment = SimulatedKitchen(task=settings.task, kitchen=settings.kitchen, seed=settings.seed,
                                   pictures=pictures is not None, joint_speed=joint_speed)
    viewer = page = None
    ending = ""  # what the page says at the end: the summary, or why the session stopped
    try:
        if args.web and person:  # the page's server and its 3D view (the meshcat mirror)
            from dialog.web.session import WebPage

            page = WebPage.for_session(args, environment, out=out)
            viewer = page.viewer
        else:
            viewer = start_viewer(args, environment.world)
        observers = page.observers if page is not None else () if viewer is None else (viewer,)
        manager, records = open_session(settings, environment, path, resume=args.resume is not None,
                                        pictures=None if pictures is None else str(pictures),
                                        input_stream=input_stream, output_stream=out, say=None,
                                        observers=observers, lock=lock,
                                        teacher=None if page is None else page.teacher)
        manager.say = _narrator(manager.teacher, out, person)
        allocation = f"{settings.turns} turns" if settings.seconds is None else \
            f"{settings.seconds:g} s with embodied costs (at most {settings.turns} turns)"
        intro = (f"Teaching '{settings.task}' ({', '.join(environment.concepts)}) in {settings.kitchen}: "
                 f"{allocation}, budget {settings.budget:g}, {scene_size(environment.world.task)}, "
                 f"strategy {settings.strategy}"
                 f"{'' if settings.weights is None else ' with the weights in ' + settings.weights['file']}. "
                 f"Transcript: {path}")
        plain = words.intro(environment.concepts, settings.turns) if page is not None else None
        if records:
            intro += f" (resuming after turn {len(records)})"
        if len(records) >= settings.turns:
            intro = (f"{path}: the session is already finished ({len(records)} of {settings.turns} turns); "
                     "nothing to resume")
            plain = "This session is already finished."
        elif records and settings.seconds is not None and records[-1].get("ended", 0.0) >= settings.seconds:
            intro = (f"{path}: the session is already finished (its {settings.seconds:g} s are used up); "
                     "nothing to resume")
            plain = "This session is already finished."
        _announce(manager, page, intro, plain)
        if page is not None and records:  # the page shows the conversation so far
            page.teacher.recall(records, environment.concepts, environment.feature_names)
        if person and len(records) < settings.turns and not manager.out_of_time():
            _announce(manager, page, "Type 'help' at any question for what you can answer; 'quit' saves and stops.",
                      "")
        again = continue_command(["teach", "--resume", path], args,
                                 UNRECORDED_TEACH_OPTIONS + web_continue_options(args))
        try:
            result = manager.run(replay=records)
        except KeyboardInterrupt:
            ending = f"Interrupted. The session is saved; continue it with: {again}"
            _announce(manager, page, f"\n{ending}", "")
            if page is not None:
                ending = "The session was interrupted. What you taught is saved; it can go on later from there."
            return 130
        except OutputPathError as error:
            ending = (f"{error}. The completed turns are saved; once that is fixed, continue with: {again}")
            stopped = OutputPathError(ending)
            if page is not None:
                ending = "The session stopped: the computer could not save the next turn. The turns before are saved."
            raise stopped from None
        finally:
            manager.transcript.close()
        if manager.replay_mismatches:
            _announce(manager, page, f"(note: on {manager.replay_mismatches} replayed turn(s) the strategy would now "
                                     "ask something else; the recorded questions were kept)", "")
        saved = f"Session saved after {result.completed} of {result.turns} turns. Continue it with: {again}"
        plain_saved = (f"The session is saved after {result.completed} of {result.turns} turns; it can go on later "
                       "from there.")
        if result.quit:
            _announce(manager, page, saved, plain_saved)
        summary = (f"Accuracy on {settings.task} held-out scenes: {result.accuracy:.1%} (chance "
                   f"{1 / len(environment.concepts):.0%}); budget spent {result.budget_spent:g} of "
                   f"{settings.budget:g}; questions: {questions_in_words(result.queries)}; "
                   f"{session_time(manager.clock, result.seconds, records)}.")
        plain_summary = (f"The robot now names {result.accuracy:.0%} of the objects in new scenes correctly "
                         f"(guessing would get {1 / len(environment.concepts):.0%}). Thank you!")
        _announce(manager, page, summary, plain_summary)
        ending = f"{saved} {summary}" if result.quit else summary
        if page is not None:  # the page's last words: plain, without the task, the files or the command
            ending = f"{plain_saved} {plain_summary}" if result.quit else plain_summary
        if args.json:
            print_json({"seed": result.seed, "strategy": result.strategy, "turns": result.turns,
                              "completed": result.completed, "quit": result.quit, "budget_spent": result.budget_spent,
                              "queries": result.queries, "accuracy": round(result.accuracy, 6),
                              "transcript": str(path), "seconds": round(result.seconds, 3)}, file=out)
        if page is None:
            hold_viewer(args, viewer, input_stream)
    finally:
        if page is not None:
            page.close(ending)
        else:
            stop_viewer(viewer)
        environment.close()
    return 0


def _announce(manager, page, text: str, plain: str | None = None) -> None:
    """``text`` as the session says it; with a page, it goes to the terminal (the researcher's) and the page
    says ``plain`` instead (nothing when empty): the page names no task, strategy, file or command."""
    if page is None or plain is None:
        manager.say(text)
        return
    page.teacher.researcher(text)
    if plain:
        page.teacher.say(plain, echo=False)


def _narrator(teacher, out, person: bool):
    """Progress lines: everything for a scripted run; scene changes and quiet turns for a person."""
    def say(text: str) -> None:
        if person and text.startswith("Turn") and "stays quiet" not in text and "ended the session" not in text:
            return
        if hasattr(teacher, "say"):
            teacher.say(text)
        else:
            print(text, file=out, flush=True)
    return say
