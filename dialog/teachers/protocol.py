"""The one teacher interface, and the two abilities a teacher may add to it.

A teacher is shown a :class:`~dialog.language.questions.Prompt`, answers with one line
of text at a time (``listen``; None means no more input, or no answer before
the deadline), and hears the robot's replies (``tell``). The same parser reads
every teacher's lines, so scripted runs exercise what a person would type.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from dialog.language.questions import Prompt


@runtime_checkable
class Teacher(Protocol):
    """The one teacher interface: shown a prompt, answers one line at a time, hears the robot's replies."""

    def show(self, prompt: Prompt) -> None: ...

    def listen(self, prompt: Prompt, deadline: float | None) -> str | None: ...

    def tell(self, text: str) -> None: ...


@runtime_checkable
class FastForwards(Protocol):
    """A teacher whose answers come from a seeded stream: on resume it skips the answers already recorded."""

    def fast_forward(self, prompt: Prompt) -> None: ...


@runtime_checkable
class ReportsChannels(Protocol):
    """A teacher whose lines come by different ways (the page: click, button, typed): after each ``listen``,
    ``answer_channel()`` says how that line came, ``{"channel": ..., "page_seconds": ...}``."""

    def answer_channel(self) -> dict: ...


def checked_teacher(teacher) -> Teacher:
    """``teacher`` itself when it is a :class:`Teacher`; anything else is a TypeError naming what it lacks."""
    if isinstance(teacher, Teacher):
        return teacher
    raise TypeError(f"{type(teacher).__name__} is not a teacher: it needs show, listen and tell")
