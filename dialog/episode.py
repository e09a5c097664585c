"""The parts of an episode made from their settings: its teacher, of any kind.

The teachers live in ``dialog.teachers``; this factory sits above them because a replay teacher reads a
transcript (``dialog.transcripts``), which itself records the teachers' answers.
"""

from __future__ import annotations

import numpy as np

from dialog.teachers.protocol import Teacher
from dialog.teachers.scripted import SCRIPTED_OPTIONS, OracleTeacher, ReplayTeacher, ScriptedTeacher
from dialog.teachers.terminal import TerminalTeacher
from dialog.transcripts.jsonl import read_session
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
        return ReplayTeacher(read_session(transcript)[1])
    if rng is None:
        raise TypeError(f"a {kind} teacher needs its random generator (rng=)")
    if kind == "oracle":
        return OracleTeacher(rng, clock=clock, answer_delays=answer_delays)
    return ScriptedTeacher(rng, clock=clock, answer_delays=answer_delays,
                           **{name: float(value) for name, value in options.items()})
