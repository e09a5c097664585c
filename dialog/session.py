"""A teaching session: its settings, its teacher and its manager, new or resumed from a transcript.

The settings go into the transcript's header, so that ``teachbot teach --resume
FILE`` can rebuild the same kitchen, strategy, teacher and random streams and
replay the recorded answers into a fresh learning state before going on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from dialog.clock import VirtualClock, WallClock
from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.teachers import ReplayTeacher, ScriptedTeacher
from dialog.terminal import TerminalTeacher
from dialog.transcript import TranscriptWriter, read_session
from learning.actions import DEFAULT_COSTS
from learning.strategies import make_strategy

TEACHERS = ("terminal", "scripted", "replay")
SCRIPTED_OPTIONS = ("mislabel_rate", "dont_know_rate", "feature_quality", "answer_delay")


@dataclass
class SessionSettings:
    """Everything that defines a session; stored in the transcript header."""

    task: str = "pack-lunchbox"
    kitchen: str = "kitchen-1"
    strategy: str = "active"
    seed: int = 0
    turns: int = 30
    budget: float = 40.0
    change_every: int = 5
    realtime: float | None = None
    fetch_from_pantry: bool = True
    costs: dict = field(default_factory=lambda: dict(DEFAULT_COSTS))
    teacher: dict = field(default_factory=lambda: {"kind": "terminal"})

    def __post_init__(self):
        kind = self.teacher.get("kind")
        if kind not in TEACHERS:
            raise ValueError(f"teacher '{kind}' is not one of {', '.join(TEACHERS)}")
        unknown = sorted(set(self.teacher) - {"kind", "transcript", *SCRIPTED_OPTIONS})
        if unknown:
            raise ValueError(f"unknown teacher options {unknown}; accepted: {', '.join(SCRIPTED_OPTIONS)}, transcript")
        if kind == "replay" and not self.teacher.get("transcript"):
            raise ValueError("a replay teacher needs the transcript to replay (--replay FILE)")

    def config(self, pictures: str | None) -> EpisodeConfig:
        return EpisodeConfig(turns=self.turns, budget=self.budget, change_every=self.change_every, seed=self.seed,
                             costs=dict(self.costs), realtime=self.realtime, pictures=pictures,
                             fetch_from_pantry=self.fetch_from_pantry)

    def header(self) -> dict:
        return {"command": "teach", "task": self.task, "kitchen": self.kitchen, "teacher": dict(self.teacher)}

    @classmethod
    def from_header(cls, header: dict | None, path) -> SessionSettings:
        """Settings of a recorded session; a transcript without a usable header gets a clear message."""
        if not header:
            raise ValueError(f"{path} has no session header; only transcripts written by teachbot can be resumed")
        names = {f for f in cls.__dataclass_fields__}
        values = {key: header[key] for key in names if key in header}
        missing = sorted({"task", "kitchen", "strategy", "seed", "turns", "budget", "change_every"} - set(values))
        if missing:
            raise ValueError(f"{path}: the session header lacks {', '.join(missing)}")
        return cls(**values)


def check_compatible(header: dict, environment, path) -> None:
    """A recorded session can only go on with the same concepts and features."""
    concepts, features = header.get("concepts"), header.get("features")
    if concepts is not None and list(concepts) != list(environment.concepts):
        raise ValueError(f"{path} was recorded with the concepts {concepts}; this task has "
                         f"{list(environment.concepts)}")
    if features is not None and features != len(environment.feature_names):
        raise ValueError(f"{path} was recorded with {features} features; this kitchen gives "
                         f"{len(environment.feature_names)} (the feature catalogue changed since)")


def make_clock(settings: SessionSettings, start: float = 0.0):
    """Wall time for a person or a real-time session; virtual (deterministic) time for scripted runs."""
    real = settings.teacher["kind"] == "terminal" or settings.realtime is not None
    return WallClock(start) if real else VirtualClock(start)


def make_teacher(settings: SessionSettings, rngs, clock, input_stream=None, output_stream=None):
    kind = settings.teacher["kind"]
    if kind == "terminal":
        return TerminalTeacher(input_stream, output_stream, clock=clock)
    if kind == "scripted":
        options = {key: settings.teacher[key] for key in SCRIPTED_OPTIONS if key in settings.teacher}
        return ScriptedTeacher(rngs["teacher"], clock=clock, **options)
    return ReplayTeacher(read_session(settings.teacher["transcript"])[1])


def open_session(settings: SessionSettings, environment, transcript_path: str | Path, *, resume: bool = False,
                 pictures: str | None = None, input_stream=None, output_stream=None, say=None,
                 observers=()) -> tuple[DialogManager, list[dict]]:
    """The manager for a new session, or for a recorded one (its turns to replay come back too)."""
    records: list[dict] = []
    start = 0.0
    if resume:
        header, records = read_session(transcript_path, tolerate_partial_tail=True)
        check_compatible(header or {}, environment, transcript_path)
        if records:
            start = float(records[-1].get("ended", records[-1].get("time", 0.0)))
    rngs = episode_generators(settings.seed)
    clock = make_clock(settings, start)
    teacher = make_teacher(settings, rngs, clock, input_stream, output_stream)
    transcript = TranscriptWriter(transcript_path, append=resume)
    manager = DialogManager(environment, teacher, make_strategy(settings.strategy), settings.config(pictures),
                            transcript, rngs, say=say or print, observers=observers, clock=clock,
                            session=settings.header())
    return manager, records

