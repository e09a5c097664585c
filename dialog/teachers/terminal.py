"""A person at the terminal: questions and tables out, one answer line in (works without a TTY too).

Input and output streams are injected. Lines are read straight from the input's
file descriptor when it has one, so that real-time mode can stop waiting at a
turn's deadline (``select``); a stream without one (``io.StringIO``) is read
line by line without a deadline. Output goes through ``rich``, which styles it
on a terminal and writes plain text anywhere else.
"""

from __future__ import annotations

import io
import os
import select
import sys

from rich.console import Console

from dialog.language.questions import Prompt

MAX_LINE_BYTES = 4 << 20  # a longer "line" is handed over as it is, the rest read as the next line
TIMEOUT = object()
COUNTDOWN_MARKS = (30, 10, 5)  # real-time mode: the seconds left at which the prompt says so again


class LineReader:
    """Reads lines from a stream, optionally with a timeout; bytes are decoded as UTF-8 (bad bytes replaced)."""

    def __init__(self, stream):
        self.stream = stream
        try:
            self.fd = stream.fileno()
        except (AttributeError, OSError, io.UnsupportedOperation, ValueError):
            self.fd = None
        self._buffer = bytearray()
        self._eof = False

    def _decode(self, raw: bytes) -> str:
        return raw.decode("utf-8", errors="replace").rstrip("\r")

    def readline(self, timeout: float | None = None):
        """The next line without its newline; None at end of input; ``TIMEOUT`` when none came in time."""
        if self.fd is None:
            line = self.stream.readline()
            return None if line == "" else line.rstrip("\r\n")
        while b"\n" not in self._buffer and not self._eof and len(self._buffer) < MAX_LINE_BYTES:
            if timeout is not None:
                ready, _, _ = select.select([self.fd], [], [], max(0.0, timeout))
                if not ready:
                    return TIMEOUT
            chunk = os.read(self.fd, 1 << 16)
            if not chunk:
                self._eof = True
            self._buffer += chunk
        cut = self._buffer.find(b"\n")
        if cut < 0:
            if not self._buffer:
                return None
            cut = len(self._buffer)
        raw = bytes(self._buffer[:cut])
        del self._buffer[:cut + 1]
        return self._decode(raw)

    def drain(self) -> int:
        """Throw away lines already typed (after a missed deadline); returns how many."""
        dropped = self._buffer.count(b"\n")
        self._buffer.clear()
        while self.fd is not None and not self._eof and select.select([self.fd], [], [], 0)[0]:
            chunk = os.read(self.fd, 1 << 16)
            if not chunk:
                self._eof = True
            dropped += chunk.count(b"\n")
        return dropped


class TerminalTeacher:
    """The person at the keyboard."""

    def __init__(self, input_stream=None, output_stream=None, clock=None, color: bool | None = None):
        self.reader = LineReader(input_stream if input_stream is not None else sys.stdin)
        output = output_stream if output_stream is not None else sys.stdout
        self.console = Console(file=output, highlight=False, markup=False, emoji=False, soft_wrap=True,
                               force_terminal=color, no_color=color is False)
        self.clock = clock
        self._missed = False
        self._shown: Prompt | None = None  # the question on screen: asked again (after undo), not reprinted
        self.show_budget = True  # a study hides the budget from its participants (dialog/study/run.py)

    def options(self) -> dict:
        return {"kind": "terminal"}

    def show(self, prompt: Prompt) -> None:
        if self._missed:
            dropped = self.reader.drain()
            if dropped:
                self.say(f"(ignored {dropped} line(s) typed after the time ran out)")
            self._missed = False
        if prompt is self._shown:
            return  # asked again after an undo: "Taken back: ..." already repeated the question
        self._shown = prompt
        self.console.print()
        status = f"Turn {prompt.turn} of {prompt.turns}"
        if self.show_budget:
            status += f" · budget left {prompt.budget_left:g}"
        if prompt.deadline is not None and self.clock is not None:
            status += f" · {max(0.0, prompt.deadline - self.clock.now()):.0f} s to answer"
        self.console.print(status, style="dim")
        for line in prompt.details:
            self.console.print(f"  {line}")
        self.console.print(f"Robot: {prompt.text}", style="bold")

    def say(self, text: str) -> None:
        """A line from the session itself (progress, the summary)."""
        self.console.print(text)

    def _prompt(self, seconds_left: float | None) -> None:
        self.console.print(_prompt_text(seconds_left), end="")
        self.console.file.flush()

    def tell(self, text: str) -> None:
        self.console.print(f"Robot: {text}", style="cyan")

    def listen(self, prompt: Prompt, deadline: float | None) -> str | None:
        """One line typed by the person; in real-time mode the prompt counts down ("[23 s left] > ") and says
        again how long is left at each of COUNTDOWN_MARKS seconds."""
        timeout = None
        if deadline is not None and self.clock is not None:
            timeout = deadline - self.clock.now()
        self._prompt(timeout)
        marks = [mark for mark in COUNTDOWN_MARKS if timeout is not None and mark < timeout]
        while True:
            line = self.reader.readline(None if timeout is None else max(timeout - (marks[0] if marks else 0), 0))
            if line is not TIMEOUT or not marks:
                break
            timeout = marks.pop(0)  # as scheduled: a virtual clock does not move while we wait
            self.console.print()
            self._prompt(timeout)
        if line is TIMEOUT:
            self._missed = True
            self.console.print()
            return None
        if line is None:
            self.console.print()
        elif self.reader.fd is None or not _echoes(self.reader.fd):
            self.console.print(line[:200] + (" ..." if len(line) > 200 else ""), style="dim")
        return line


def _prompt_text(seconds_left: float | None) -> str:
    return "> " if seconds_left is None else f"[{max(seconds_left, 0):.0f} s left] > "


def _echoes(fd: int) -> bool:
    """Whether the terminal already shows what is typed (a TTY does; a pipe or file doesn't)."""
    try:
        return os.isatty(fd)
    except OSError:
        return False
