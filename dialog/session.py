"""A teaching session: its settings, its teacher and its manager, new or resumed from a transcript.

The settings go into the transcript's header, so that ``teachbot teach --resume
FILE`` can rebuild the same kitchen, strategy, teacher and random streams and
replay the recorded answers into a fresh learning state before going on.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from bullet_world.datafiles import available, resolve
from dialog.clock import VirtualClock, WallClock
from dialog.episode import build_episode, embodied_timing, make_teacher
from dialog.manager import DialogManager, episode_generators
from dialog.settings import EpisodeSettings
from dialog.teachers.scripted import SCRIPTED_OPTIONS
from dialog.transcripts.jsonl import VERSION, TranscriptWriter, read_numbered_session
from dialog.transcripts.records import check_turn_record
from dialog.user_weights import weights_from_header
from learning.actions import DEFAULT_COSTS
from learning.errors import DataFileError, SettingsError, TranscriptError
from learning.rl.policy_file import policy_digest
from learning.strategies import PLUGIN_FORM, STRATEGY_NAMES, check_strategy_name, is_plugin_spec
from learning.strategies.rl_questioner import PREFIX as RL_PREFIX

TEACHERS = ("terminal", "scripted", "replay")  # the kinds a teach session records


@dataclass(frozen=True)
class SessionSettings(EpisodeSettings):
    """Everything that defines a teach session: the episode settings and the teacher; stored in the transcript
    header."""

    teacher: dict = field(default_factory=lambda: {"kind": "terminal"})

    def __post_init__(self):
        super().__post_init__()
        kind = self.teacher.get("kind")
        if kind not in TEACHERS:
            raise SettingsError(f"teacher '{kind}' is not one of {', '.join(TEACHERS)}")
        unknown = sorted(set(self.teacher) - {"kind", "transcript", *SCRIPTED_OPTIONS})
        if unknown:
            raise SettingsError(f"unknown teacher options {unknown}; accepted: {', '.join(SCRIPTED_OPTIONS)}, "
                                "transcript")
        if kind == "replay" and not self.teacher.get("transcript"):
            raise SettingsError("a replay teacher needs the transcript to replay (--replay FILE)")

    def header(self) -> dict:
        header = {"command": "teach", "task": self.task, "kitchen": self.kitchen, "teacher": dict(self.teacher)}
        return header if self.weights is None else header | {"weights": dict(self.weights)}

    @classmethod
    def from_header(cls, header: dict | None, path) -> SessionSettings:
        """Settings of a recorded session; a header that is missing or malformed is refused as ``FILE: line 1: ...``."""
        if not header:
            raise TranscriptError(f"{path} has no session header; only transcripts written by teachbot can be resumed")
        check_header(header, path)
        names = {f for f in cls.__dataclass_fields__}
        return cls(**{key: header[key] for key in names if key in header})


REQUIRED = ("task", "kitchen", "strategy", "seed", "turns", "budget", "change_every")


def check_header(header: dict, path) -> None:
    """Every field of a session header has its type and a value a session accepts."""
    def refuse(name: str, expected: str):
        value = json.dumps(header.get(name))[:80]
        return TranscriptError(f"{path}: line 1: the session header's '{name}' is {value} (expected {expected})")

    missing = [name for name in REQUIRED if name not in header]
    if missing:
        raise TranscriptError(f"{path}: line 1: the session header lacks {', '.join(missing)}")
    if header.get("version", VERSION) != VERSION:
        raise refuse("version", f"{VERSION}; this teachbot reads version {VERSION} transcripts")
    if header.get("command", "teach") != "teach":
        raise refuse("command", "'teach': only teach sessions can be resumed")
    for name, folder in (("task", "tasks"), ("kitchen", "kitchens")):
        if not _known_data_file(folder, header[name]):
            raise refuse(name, f"one of {', '.join(available(folder))}")
    if isinstance(header["strategy"], str) and header["strategy"].startswith(RL_PREFIX):
        _check_policy(header, path, refuse)
    elif is_plugin_spec(header["strategy"]):  # module.path:ClassName: it must still import and build
        try:
            check_strategy_name(header["strategy"])
        except SettingsError as error:
            raise TranscriptError(f"{path}: line 1: the session header's strategy can't be loaded now: {error}") \
                from None
    elif header["strategy"] not in STRATEGY_NAMES:
        raise refuse("strategy", f"one of {', '.join(STRATEGY_NAMES)}, {RL_PREFIX}FILE, or {PLUGIN_FORM}")
    if not (_is_int(header["seed"]) and header["seed"] >= 0):
        raise refuse("seed", "a whole number of 0 or more")
    for name in ("turns", "change_every"):
        if not (_is_int(header[name]) and header[name] >= 1):
            raise refuse(name, "a whole number of at least 1")
    if not (_is_number(header["budget"]) and header["budget"] >= 0):
        raise refuse("budget", "a finite number of cost units, 0 or more")
    realtime = header.get("realtime")
    if realtime is not None and not (_is_number(realtime) and realtime > 0):
        raise refuse("realtime", "null or a positive number of seconds per turn")
    seconds = header.get("seconds")
    if seconds is not None and not (_is_number(seconds) and seconds > 0 and realtime is None):
        raise refuse("seconds", "null or a positive number of seconds (embodied costs; not with realtime)")
    for name in ("fetch_from_pantry", "until_budget_spent"):
        if not isinstance(header.get(name, True), bool):
            raise refuse(name, "true or false")
    costs = header.get("costs", DEFAULT_COSTS)
    if not (isinstance(costs, dict) and set(costs) == set(DEFAULT_COSTS)
            and all(_is_number(v) and v >= 0 for v in costs.values())):
        raise refuse("costs", f"a cost of 0 or more for each of {', '.join(DEFAULT_COSTS)}")
    concepts = header.get("concepts", [])
    if not (isinstance(concepts, list) and all(isinstance(c, str) for c in concepts)):
        raise refuse("concepts", "a list of concept names")
    if "features" in header and not (_is_int(header["features"]) and header["features"] >= 1):
        raise refuse("features", "the number of features, at least 1")
    _check_teacher(header.get("teacher", {"kind": "terminal"}), refuse)
    weights_from_header(header.get("weights"), path)


def _check_policy(header: dict, path, refuse) -> None:
    """A trained questioner's session resumes only with the very policy file it was recorded with."""
    recorded, file = header.get("policy"), header["strategy"][len(RL_PREFIX):]
    if not (isinstance(recorded, dict) and recorded.get("file") == file and isinstance(recorded.get("sha256"), str)):
        raise refuse("policy", f"the file {file} and its SHA-256, as teachbot records them for {header['strategy']}")
    try:
        now = policy_digest(file)
    except OSError:
        raise TranscriptError(f"{path}: the session was recorded with the questioner policy {file}, which can't be "
                              "read now; restore that file to resume") from None
    if now != recorded["sha256"]:
        raise TranscriptError(f"{path}: the questioner policy {file} changed since the session was recorded; restore "
                              "it, or start a new session without --resume")


def _check_teacher(teacher, refuse) -> None:
    if not isinstance(teacher, dict) or teacher.get("kind") not in TEACHERS:
        raise refuse("teacher", f"a table whose kind is one of {', '.join(TEACHERS)}")
    unknown = sorted(set(teacher) - {"kind", "transcript", *SCRIPTED_OPTIONS})
    if unknown:
        raise refuse("teacher", f"no options but kind, transcript, {', '.join(SCRIPTED_OPTIONS)}; "
                                f"unknown: {', '.join(unknown)}")
    for name in SCRIPTED_OPTIONS:
        value = teacher.get(name, 0.0)
        top = math.inf if name == "answer_delay" else 1.0
        if not (_is_number(value) and 0 <= value <= top):
            raise refuse("teacher", f"{name} {'zero or more seconds' if top > 1 else 'between 0 and 1'}, "
                                    f"not {json.dumps(value)}")
    if teacher["kind"] == "replay" and not (isinstance(teacher.get("transcript"), str) and teacher["transcript"]):
        raise refuse("teacher", "the path of the transcript a replay teacher answers from")


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _known_data_file(folder: str, name) -> bool:
    if not isinstance(name, str) or not name:
        return False
    try:
        return resolve(folder, name).is_file()
    except DataFileError:
        return False


def check_compatible(header: dict, environment, path) -> None:
    """A recorded session can only go on with the same concepts and features."""
    concepts, features = header.get("concepts"), header.get("features")
    if concepts is not None and list(concepts) != list(environment.concepts):
        raise TranscriptError(f"{path}: line 1: the session was recorded with the concepts {concepts}; this task "
                              f"has {list(environment.concepts)}")
    if features is not None and features != len(environment.feature_names):
        raise TranscriptError(f"{path}: line 1: the session was recorded with {features} features; this kitchen "
                              f"gives {len(environment.feature_names)} (the feature catalogue changed since)")


def make_clock(settings: SessionSettings, start: float = 0.0):
    """Wall time for a person or a real-time session; virtual (deterministic) time for scripted runs."""
    real = settings.teacher["kind"] == "terminal" or settings.realtime is not None
    if real and settings.seconds is not None:  # embodied costs: a person's real time plus the arm's motion
        return WallClock(start, counts_simulated=True)
    return WallClock(start) if real else VirtualClock(start)


def session_teacher(settings: SessionSettings, rngs, clock, input_stream=None, output_stream=None):
    """The session's teacher, from its recorded kind and options (``dialog.episode.make_teacher``)."""
    kind = settings.teacher["kind"]
    options = {key: settings.teacher[key] for key in SCRIPTED_OPTIONS if key in settings.teacher and kind == "scripted"}
    delays = embodied_timing(settings.seconds).answer_delays if kind == "scripted" else None  # embodied costs
    return make_teacher(kind, rng=rngs["teacher"], clock=clock, transcript=settings.teacher.get("transcript"),
                        input_stream=input_stream, output_stream=output_stream, answer_delays=delays, **options)


def open_session(settings: SessionSettings, environment, transcript_path: str | Path, *, resume: bool = False,
                 pictures: str | None = None, input_stream=None, output_stream=None, say=None,
                 observers=(), lock=None, teacher=None) -> tuple[DialogManager, list[dict]]:
    """The manager for a new session, or for a recorded one with its turns already replayed (they come back too).

    ``lock`` is the transcript's :class:`TranscriptLock` when the caller took it already (one writer per file).
    ``teacher`` stands in for the settings' person (the page of ``--web``); its ``clock`` is set to the session's.

    Resuming checks every recorded turn, then replays it against the rebuilt
    episode; a malformed or diverging record is refused as ``FILE: line N: ...``.
    """
    numbered: list[tuple[int, dict]] = []
    start = 0.0
    if resume:
        header, numbered = read_numbered_session(transcript_path, tolerate_partial_tail=True)
        check_compatible(header or {}, environment, transcript_path)
        for expected, (line, record) in enumerate(numbered, start=1):
            try:
                check_turn_record(record, expected, settings.turns, environment.concepts, environment.feature_names)
            except TranscriptError as error:
                raise TranscriptError(f"{transcript_path}: line {line}: {error}") from None
        if numbered:
            start = float(numbered[-1][1].get("ended", numbered[-1][1].get("time", 0.0)))
    rngs = episode_generators(settings.seed)
    clock = make_clock(settings, start)
    if teacher is None:
        teacher = session_teacher(settings, rngs, clock, input_stream, output_stream)
    elif getattr(teacher, "clock", False) is None:
        teacher.clock = clock
    transcript = TranscriptWriter(transcript_path, append=resume, lock=lock)
    manager = build_episode(settings, environment, teacher, transcript, rngs=rngs, say=say or print,
                            observers=observers, clock=clock, pictures=pictures, session=settings.header())
    try:
        replay(manager, numbered, transcript_path)
    except BaseException:
        transcript.close()
        raise
    return manager, [record for _, record in numbered]


def replay(manager: DialogManager, numbered: list[tuple[int, dict]], path) -> None:
    """Re-apply recorded turns quietly; one that diverges from the rebuilt episode names its line."""
    manager.begin()
    speak, manager.say = manager.say, lambda _text: None
    try:
        for line, record in numbered:
            try:
                manager.replay_turn(record)
            except TranscriptError as error:
                raise TranscriptError(f"{path}: line {line}: {error}") from None
    finally:
        manager.say = speak
