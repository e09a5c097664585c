"""Ctrl-C, SIGTERM and SIGHUP end a ``teachbot`` command the same clean way, at any moment.

Inside :class:`CleanSignals`, SIGINT raises ``KeyboardInterrupt`` and SIGTERM or SIGHUP raise
:class:`Stopped`, once: ``finally`` blocks run, so child processes are stopped and transcripts
closed. A second signal while that clean-up runs ends the process at once (exit 128 + signal).
An interrupt that lands where Python can't raise it (in a ``__del__``, say) is delivered again
instead of being printed as "Exception ignored".
"""

from __future__ import annotations

import os
import signal
import sys
import threading

HANDLED_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Stopped(BaseException):
    """SIGTERM or SIGHUP arrived: unwind like Ctrl-C and exit with 128 + the signal number."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum

    @property
    def signal_name(self) -> str:
        return signal.Signals(self.signum).name


def exit_code(signum: int) -> int:
    """The shell's exit code for a process ended by ``signum`` (130 for Ctrl-C)."""
    return 128 + int(signum)


def _exit_now(signum: int, frame=None) -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(exit_code(signum))


class CleanSignals:
    """Turn the first SIGINT/SIGTERM/SIGHUP into an exception; later ones end the process at once.

    ``keep_after=True`` leaves "end at once" handlers in place on the way out, for the
    interpreter's shutdown when this process is the ``teachbot`` program itself; otherwise
    the handlers found on entry are restored. Outside the main thread it does nothing.
    """

    def __init__(self, keep_after: bool = False):
        self.keep_after = keep_after
        self.signum: int | None = None  # the first signal that arrived
        self._previous: dict[int, object] = {}
        self._previous_hook = None
        self._active = False
        self._redelivering = False

    def __enter__(self) -> CleanSignals:
        if threading.current_thread() is not threading.main_thread():
            return self
        self._active = True
        for signum in HANDLED_SIGNALS:
            self._previous[signum] = signal.signal(signum, self._on_signal)
        self._previous_hook = sys.unraisablehook
        sys.unraisablehook = self._on_unraisable
        return self

    def __exit__(self, *exc) -> None:
        if not self._active:
            return
        for signum, previous in self._previous.items():
            signal.signal(signum, _exit_now if self.keep_after else previous)
        sys.unraisablehook = self._previous_hook
        self._active = False

    def _on_signal(self, signum: int, frame) -> None:
        if self.signum is not None and not self._redelivering:
            _exit_now(signum)
        self.signum, self._redelivering = signum, False
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Stopped(signum)

    def _on_unraisable(self, unraisable) -> None:
        error = unraisable.exc_value
        if self.signum is not None and isinstance(error, (KeyboardInterrupt, Stopped)):
            self._redelivering = True  # it never reached the command: raise it again where it can unwind
            signal.raise_signal(self.signum)
            return
        self._previous_hook(unraisable)
