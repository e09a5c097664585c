"""An episode made from its settings, in one place (issue 25): ``build_episode`` wires the manager,
``make_teacher`` builds a teacher of any kind, ``embodied_timing`` gives an allocation in seconds its clock.

demo, teach, regress, study, expert, the Gymnasium environment and the scripts all call ``build_episode``,
so the strategy comes from ``EpisodeSettings.build_strategy`` (DT with a user's weights, else
``learning.make_strategy``, which decodes every form of a name: a preset, ``NAME+turns``, ``rl:FILE``,
``module:Class``) and the allocation from ``settings.config()``.
The teachers live in ``dialog.teachers``; this module sits above them because a replay teacher reads a
transcript (``dialog.transcripts``), which itself records the teachers' answers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dialog.clock import VirtualClock
from dialog.embodied import load_embodied_costs
from dialog.manager import DialogManager, episode_generators
from dialog.settings import EpisodeSettings
from dialog.teachers.protocol import Teacher
from dialog.teachers.scripted import SCRIPTED_OPTIONS, OracleTeacher, ReplayTeacher, ScriptedTeacher
from dialog.teachers.terminal import TerminalTeacher
from dialog.transcripts.records import read_replay_records
from learning.errors import SettingsError

TEACHER_KINDS = ("terminal", "scripted", "oracle", "replay")


def make_teacher(kind: str, *, rng: np.random.Generator | None = None, clock=None, transcript=None,
                 input_stream=None, output_stream=None, answer_delays: dict | None = None, **options) -> Teacher:
    """The one teacher factory, for teach sessions, expert episodes and suites.

    ``terminal``: a person (``input_stream``/``output_stream``, the terminal by default); ``scripted``: an
    oracle with ``SCRIPTED_OPTIONS`` drawn from ``rng``; ``oracle``: a perfect one; ``replay``: the lines of the
    ``transcript`` file. An unknown kind or option is a :class:`SettingsError` naming what is accepted.
    ``answer_delays`` (embodied costs): a scripted or oracle teacher's mean answer seconds per query kind.
    """
    if kind not in TEACHER_KINDS:
        raise SettingsError(f"teacher '{kind}' is not one of {', '.join(TEACHER_KINDS)}")
    accepted = SCRIPTED_OPTIONS if kind == "scripted" else ()
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise SettingsError(f"a {kind} teacher does not take the options {', '.join(unknown)}; accepted: "
                            f"{', '.join(accepted) or 'none'}")
    if kind == "terminal":
        return TerminalTeacher(input_stream, output_stream, clock=clock)
    if kind == "replay":
        if not transcript:
            raise SettingsError("a replay teacher needs the transcript to replay (--replay FILE)")
        return ReplayTeacher(read_replay_records(transcript))
    if rng is None:
        raise TypeError(f"a {kind} teacher needs its random generator (rng=)")
    if kind == "oracle":
        return OracleTeacher(rng, clock=clock, answer_delays=answer_delays)
    return ScriptedTeacher(rng, clock=clock, answer_delays=answer_delays,
                           **{name: float(value) for name, value in options.items()})


@dataclass(frozen=True)
class EmbodiedTiming:
    """What an allocation in seconds (embodied costs, thesis §8.2.2) adds to an episode: one virtual clock for
    the arm, the turns and the teacher's answers, the teacher's mean answer seconds per query kind, and the
    arm's joint speed. All None for an episode in turns."""

    clock: VirtualClock | None = None
    answer_delays: dict | None = None
    joint_speed: float | None = None


def embodied_timing(seconds: float | None) -> EmbodiedTiming:
    """The clock and the answer times of an allocation in ``seconds`` (None: time in turns, nothing added)."""
    if seconds is None:
        return EmbodiedTiming()
    costs = load_embodied_costs()
    return EmbodiedTiming(VirtualClock(), costs.answer, costs.joint_speed)


def build_episode(settings: EpisodeSettings, environment, teacher: Teacher, transcript, *, strategy=None,
                  rngs: dict[str, np.random.Generator] | None = None, clock=None, say=print, observers=(),
                  pictures: str | None = None, session: dict | None = None) -> DialogManager:
    """A ready episode: ``settings`` (allocation, seed, strategy) played in ``environment`` with ``teacher``,
    recorded in ``transcript``.

    ``strategy`` stands in for the settings' one when the caller holds a built object (the Gymnasium agent's
    slot, the expert's chooser, IRL's sampling policy); ``rngs`` default to the settings' seed's streams and
    ``clock`` to a virtual one; ``pictures`` is the folder for scene pictures; ``session`` goes into the
    transcript's header.
    """
    rngs = episode_generators(settings.seed) if rngs is None else rngs
    strategy = settings.build_strategy() if strategy is None else strategy
    return DialogManager(environment, teacher, strategy, settings.config(pictures), transcript, rngs, say=say,
                         observers=observers, clock=clock, session=session)
