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

FORMAT = "teachbot-transcript"
VERSION = 1


class TranscriptWriter:
    """Appends one JSON object per line; every write reaches the disk before returning.

    ``append=True`` continues an existing transcript (``--resume``): a last line
    cut short by a crash is dropped first, so the file stays valid JSON Lines.
    """

    def __init__(self, path: str | Path, append: bool = False):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if append and self.path.exists():
            drop_partial_tail(self.path)
            self._handle = open(self.path, "a", encoding="utf-8")
        else:
            self._handle = open(self.path, "w", encoding="utf-8")
        self.has_content = self.path.stat().st_size > 0

    def write(self, record: dict) -> None:
        self._handle.write(json.dumps(record, ensure_ascii=False) + "\n")
        self._handle.flush()
        os.fsync(self._handle.fileno())
        self.has_content = True

    def write_header(self, session: dict) -> None:
        """The session header; written once, as the first line."""
        if self.has_content:
            raise ValueError(f"{self.path}: the session header must be the first line")
        self.write({"session": {"format": FORMAT, "version": VERSION, **session}})

    def close(self) -> None:
        self._handle.close()

    def __enter__(self) -> TranscriptWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


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


def read_session(path: str | Path, tolerate_partial_tail: bool = False) -> tuple[dict | None, list[dict]]:
    """The header (None for a transcript without one) and the turn records, in order.

    A line that is not JSON raises a message naming its number, except a last
    line without a newline when ``tolerate_partial_tail`` (a crash mid-write).
    """
    header, records = None, []
    with open(path, encoding="utf-8", errors="replace") as handle:
        lines = handle.readlines()
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as error:
            if tolerate_partial_tail and number == len(lines) and not line.endswith("\n"):
                break
            raise ValueError(f"{path}: line {number} is not a JSON record ({error.msg})") from None
        if not isinstance(record, dict):
            raise ValueError(f"{path}: line {number} is not a JSON object")
        if "session" in record:
            if number != 1 or header is not None:
                raise ValueError(f"{path}: line {number} is a session header; only line 1 may be one")
            header = record["session"]
            if not isinstance(header, dict) or header.get("format") != FORMAT:
                raise ValueError(f"{path}: line 1 is not a {FORMAT} header")
            continue
        if "turn" not in record:
            raise ValueError(f"{path}: line {number} has no 'turn'")
        records.append(record)
    return header, records


def read_transcript(path: str | Path) -> list[dict]:
    """The turn records of a transcript (the session header is skipped)."""
    return read_session(path)[1]
