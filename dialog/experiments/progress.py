"""One progress line for a whole sweep: episodes done of the total, episodes per second and the time left.

``teachbot regress`` (every data seed of ``--data-seeds``) and ``make experiments`` (every suite of the
plan) count all their episodes up front and advance one :class:`SweepProgress`. On a terminal the line is
rewritten in place a few times a second; elsewhere (CI, a pipe, a log file) a new line is written at most
every ``LOG_EVERY`` seconds, and one at the end, so a long run's log grows by a line or two a minute.
The line goes to standard error: standard output may carry JSON.

A ``teachbot regress`` started by ``make experiments`` reports each finished episode as a line
``EVENT`` on its standard error (:class:`EventProgress`); the parent reads them and advances its own line.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable
from typing import Protocol, TextIO

LOG_EVERY = 30.0  # seconds between lines when standard error is not a terminal
REDRAW_EVERY = 0.2  # seconds between redraws on a terminal
EVENT = "teachbot-progress: episode done"  # one line per episode, for a parent process


class Progress(Protocol):
    """What a runner tells the progress of a run: an episode done, what runs now, the end."""

    def advance(self, count: int = 1) -> None: ...

    def describe(self, doing: str) -> None: ...

    def close(self) -> None: ...


def clock_time(seconds: float) -> str:
    """``h:mm:ss`` (``m:ss`` under an hour)."""
    whole = max(int(round(seconds)), 0)
    hours, rest = divmod(whole, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"


def progress_line(done: int, total: int, seconds: float, what: str = "episodes", doing: str = "") -> str:
    """``episodes 40/120 (33 %), 2.50/s, 0:16 elapsed, ETA 0:32 · doing``: the rate and ETA once one is done."""
    share = f" ({done / total:.0%})" if total else ""
    line = f"{what} {done}/{total}{share}, {clock_time(seconds)} elapsed"
    if done and seconds > 0:
        rate = done / seconds
        line += f", {rate:.2f}/s, ETA {clock_time((total - done) / rate)}"
    return line + (f" · {doing}" if doing else "")


class SweepProgress:
    """The one progress line of a run of ``total`` episodes; ``advance()`` after each, ``close()`` at the end."""

    def __init__(self, total: int, what: str = "episodes", stream: TextIO | None = None,
                 clock: Callable[[], float] = time.perf_counter, interactive: bool | None = None):
        self.total, self.what, self.done = int(total), what, 0
        self.stream = sys.stderr if stream is None else stream
        self.interactive = _is_terminal(self.stream) if interactive is None else interactive
        self._clock = clock
        self._started = clock()
        self._shown_at: float | None = None
        self._width = 0
        self.doing = ""

    def advance(self, count: int = 1) -> None:
        self.done += count
        self._show(final=False)

    def describe(self, doing: str) -> None:
        """What runs now (a suite, a data seed), shown after the figures."""
        self.doing = doing
        self._show(final=False)

    def close(self) -> None:
        self._show(final=True)

    def note(self, text: str, out: TextIO | None = None) -> None:
        """``text`` as a line of its own on ``out`` (standard output); on a terminal the progress line is
        cleared first and drawn again below it."""
        drawn = self.interactive and self._width > 0
        if drawn:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
        print(text, file=sys.stdout if out is None else out, flush=True)
        if drawn:
            self._draw(self._clock(), final=False)

    def _show(self, final: bool) -> None:
        now = self._clock()
        every = REDRAW_EVERY if self.interactive else LOG_EVERY
        if not final and self._shown_at is not None and now - self._shown_at < every:
            return
        if not final and not self.interactive and self._shown_at is None and now - self._started < every:
            return  # a log's first line comes after LOG_EVERY seconds: a short run writes only the last one
        self._draw(now, final)

    def _draw(self, now: float, final: bool) -> None:
        self._shown_at = now
        line = progress_line(self.done, self.total, now - self._started, self.what,
                             "" if final else self.doing)
        if self.interactive:
            self.stream.write("\r" + line.ljust(self._width) + ("\n" if final else ""))
            self._width = 0 if final else len(line)
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


class EventProgress:
    """For a parent process: one ``EVENT`` line on standard error per episode (``regress --progress-events``)."""

    def __init__(self, stream: TextIO | None = None):
        self.stream = sys.stderr if stream is None else stream

    def advance(self, count: int = 1) -> None:
        for _ in range(count):
            self.stream.write(EVENT + "\n")
        self.stream.flush()

    def describe(self, doing: str) -> None:
        pass

    def close(self) -> None:
        pass


def relay(lines: Iterable[str], progress: SweepProgress, out: TextIO) -> None:
    """Read a child's standard error: each ``EVENT`` line advances ``progress``, other lines go to ``out``."""
    for line in lines:
        if line.rstrip("\n") == EVENT:
            progress.advance()
        else:
            progress.note(line.rstrip("\n"), out)


class NoProgress:
    """``--no-progress``: nothing shown."""

    def advance(self, count: int = 1) -> None:
        pass

    def describe(self, doing: str) -> None:
        pass

    def close(self) -> None:
        pass


def _is_terminal(stream: TextIO) -> bool:
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())
