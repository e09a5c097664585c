"""Transcripts: JSON Lines, flushed and synced to disk before the next turn begins.

The first line is the session header ``{"session": {...}}`` (task, kitchen,
strategy, seed, allocation, teacher): enough to rebuild the episode. Every
further line is one turn record ``{"turn": n, ...}``. ``read_transcript``
returns the turn records only; ``read_session`` returns the header too.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from dialog.output_paths import path_problem, special_file, writing
from dialog.transcripts.lock import TranscriptLock
from learning.errors import OutputPathError, TranscriptError
from learning.limits import maximum

FORMAT = "teachbot-transcript"
VERSION = 1
TURN_BYTES = 16 << 10  # room for one turn record (a few kB: question, answer lines, model summary)
MAX_TRANSCRIPT_BYTES = int(maximum("turns")) * TURN_BYTES  # the turns limit (learning/data/limits.toml) times that


class TranscriptWriter:
    """Appends one JSON object per line; every write reaches the disk before returning.

    The writer holds the transcript's lock (:class:`TranscriptLock`, taken here
    unless one is handed in) until ``close``: one writer per transcript.
    ``append=True`` continues an existing transcript (``--resume``): a last line
    cut short by a crash is dropped first, so the file stays valid JSON Lines.
    A write that fails (full disk, read-only) is cut back off and raises
    :class:`OutputPathError`; every earlier line stays intact.
    """

    def __init__(self, path: str | Path, append: bool = False, lock: TranscriptLock | None = None):
        self.path = Path(path)
        self.lock = lock if lock is not None else TranscriptLock(self.path)
        try:
            with writing(self.path, "transcript"):
                if append:
                    drop_partial_tail(self.path)
                else:
                    os.ftruncate(self.lock.fd, 0)
            self.has_content = self.lock.size() > 0
        except BaseException:
            self.lock.release()
            raise

    def write(self, record: dict) -> None:
        if not self.lock.held:
            raise ValueError(f"{self.path}: the transcript is closed")
        data = memoryview(encoded_line(record))
        fd = self.lock.fd
        size = os.fstat(fd).st_size
        try:
            with writing(self.path, "transcript"):
                while data:
                    data = data[os.write(fd, data):]
                os.fsync(fd)
        except OutputPathError:
            _truncate_quietly(fd, size)  # no half line: the file stays valid JSON Lines
            raise
        self.has_content = True

    def write_header(self, session: dict) -> None:
        """The session header; written once, as the first line."""
        if self.has_content:
            raise ValueError(f"{self.path}: the session header must be the first line")
        self.write({"session": {"format": FORMAT, "version": VERSION, **session}})

    def close(self) -> None:
        self.lock.release()

    def __enter__(self) -> TranscriptWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def encoded_line(record: dict) -> bytes:
    """One JSON line in UTF-8. A string with a lone surrogate (no UTF-8 exists for it) is written as its JSON
    escape (``\\ud800``) instead, so the record is kept, exactly as it was, rather than the turn being lost."""
    try:
        return (json.dumps(record, ensure_ascii=False) + "\n").encode("utf-8")
    except UnicodeEncodeError:
        return (json.dumps(record, ensure_ascii=True) + "\n").encode("ascii")


class MemoryTranscript:
    """A transcript kept in memory (``records``, the header first): what the Gymnasium environment records
    when no file is asked for, so that thousands of training episodes do not each sync a file to disk."""

    path = Path("<memory>")

    def __init__(self) -> None:
        self.records: list[dict] = []

    @property
    def has_content(self) -> bool:
        return bool(self.records)

    def write(self, record: dict) -> None:
        self.records.append(json.loads(json.dumps(record)))  # what a file would give back

    def write_header(self, session: dict) -> None:
        if self.records:
            raise ValueError("the session header must be the first record")
        self.write({"session": {"format": FORMAT, "version": VERSION, **session}})

    def close(self) -> None:
        pass


def _truncate_quietly(fd: int, size: int) -> None:
    try:
        os.ftruncate(fd, size)
    except OSError:
        pass  # a crash-cut tail is dropped on resume anyway


def drop_partial_tail(path: Path) -> int:
    """Cut an unfinished last line (no newline) left by a crash; returns the bytes removed."""
    size = path.stat().st_size
    if size == 0:
        return 0
    with open(path, "rb+") as handle:
        handle.seek(max(0, size - 1))
        if handle.read(1) == b"\n":
            return 0
        block = min(size, 1 << 20)
        position = size
        while position > 0:
            start = max(0, position - block)
            handle.seek(start)
            chunk = handle.read(position - start)
            cut = chunk.rfind(b"\n")
            if cut >= 0:
                keep = start + cut + 1
                break
            position = start
        else:
            keep = 0
        handle.truncate(keep)
        handle.flush()
        os.fsync(handle.fileno())
    return size - keep


def read_numbered_session(path: str | Path, tolerate_partial_tail: bool = False
                          ) -> tuple[dict | None, list[tuple[int, dict]]]:
    """The header (None for a transcript without one) and each turn record with its line number, in order.

    A line that is not JSON raises a message naming its number, except a last
    line without a newline when ``tolerate_partial_tail`` (a crash mid-write).
    """
    header, records = None, []
    check_transcript_file(path)
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            lines = handle.readlines()
    except FileNotFoundError:
        raise TranscriptError(f"{path}: no such transcript; give a transcript file that teachbot wrote") from None
    except IsADirectoryError:
        raise TranscriptError(f"{path} is a folder; give a transcript file that teachbot wrote") from None
    except PermissionError:
        raise TranscriptError(f"{path}: cannot read the transcript (no permission)") from None
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as error:
            if tolerate_partial_tail and number == len(lines) and not line.endswith("\n"):
                break
            raise TranscriptError(f"{path}: line {number} is not a JSON record: {json_problem(error, line)}; every "
                                  "line of a transcript is one JSON object, as teachbot writes it") from None
        except RecursionError:
            raise TranscriptError(f"{path}: line {number} nests JSON too deeply to be a teachbot record; every line "
                                  "of a transcript is one JSON object, as teachbot writes it") from None
        if not isinstance(record, dict):
            raise TranscriptError(f"{path}: line {number} is not a JSON object")
        if "session" in record:
            if number != 1 or header is not None:
                raise TranscriptError(f"{path}: line {number} is a session header; only line 1 may be one")
            header = record["session"]
            if not isinstance(header, dict) or header.get("format") != FORMAT:
                raise TranscriptError(f"{path}: line 1 is not a {FORMAT} header")
            continue
        if "turn" not in record:
            raise TranscriptError(f"{path}: line {number} has no 'turn'")
        records.append((number, record))
    return header, records


def check_transcript_file(path: str | Path) -> None:
    """Refuse, before opening it, a transcript to read that is not a regular file of at most
    :data:`MAX_TRANSCRIPT_BYTES` (a FIFO would block, ``/dev/zero`` never ends): the checks output paths get
    (``dialog.output_paths``), for ``--resume``, ``--replay`` and a study's records alike."""
    problem = path_problem(path)
    if problem:
        raise TranscriptError(f"{str(path)[:160]}: cannot be read: {problem}")
    kind = special_file(path)
    if kind:
        raise TranscriptError(f"{path}: it is {kind}, not a regular file; give a transcript file that teachbot wrote "
                              "(nothing was read)")
    try:
        size = os.stat(path).st_size
    except OSError:
        return  # missing, or not allowed: the reader says so in its words
    if size > MAX_TRANSCRIPT_BYTES:
        raise TranscriptError(f"{path}: {size:,} bytes is more than a transcript holds (at most "
                              f"{MAX_TRANSCRIPT_BYTES:,} bytes: {MAX_TRANSCRIPT_BYTES // TURN_BYTES:,} turns of "
                              f"{TURN_BYTES:,} bytes); give a transcript file that teachbot wrote")


def json_problem(error: json.JSONDecodeError, line: str) -> str:
    """What the JSON decoder found and where, in full: "invalid control character '\\t' at column 12"."""
    reason = error.msg[0].lower() + error.msg[1:]
    reason = reason.removesuffix(" at").removesuffix(":")
    text = line.rstrip("\r\n")
    if error.pos >= len(text):
        return f"{reason} at the end of the line (column {len(text) + 1})"
    return f"{reason} {text[error.pos]!r} at column {error.pos + 1}"


def read_session(path: str | Path, tolerate_partial_tail: bool = False) -> tuple[dict | None, list[dict]]:
    """The header (None for a transcript without one) and the turn records, in order."""
    header, numbered = read_numbered_session(path, tolerate_partial_tail)
    return header, [record for _, record in numbered]


def read_transcript(path: str | Path) -> list[dict]:
    """The turn records of a transcript (the session header is skipped)."""
    return read_session(path)[1]


def refuse_foreign_transcript(path: Path, lock: TranscriptLock, command: str) -> None:
    """A command that rewrites its transcript (``demo``) rewrites only its own: a teach or expert session
    (research data) or any other file is never overwritten. ``lock`` is held on ``path``."""
    if lock.size() == 0:
        return
    with open(path, "rb") as handle:
        first = handle.readline(1 << 16)
    try:
        header = json.loads(first).get("session")
    except (ValueError, AttributeError):
        header = None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise TranscriptError(f"{path} holds something other than a teachbot transcript; a {command} does not "
                              "overwrite it (choose another --transcript)")
    if header.get("command", command) != command:
        raise TranscriptError(f"{path} holds a recorded '{header['command']}' session; a {command} does not "
                              "overwrite it (choose another --transcript)")
