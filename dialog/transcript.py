"""Transcripts: JSON Lines, one record per turn, flushed and synced before the next turn."""

from __future__ import annotations

import json
import os
from pathlib import Path


class TranscriptWriter:
    """Appends one JSON object per line; every write reaches the disk before returning."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._handle = open(self.path, "w", encoding="utf-8")

    def write(self, record: dict) -> None:
        self._handle.write(json.dumps(record, ensure_ascii=False) + "\n")
        self._handle.flush()
        os.fsync(self._handle.fileno())

    def close(self) -> None:
        self._handle.close()

    def __enter__(self) -> TranscriptWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def read_transcript(path: str | Path) -> list[dict]:
    """All records of a transcript; a line that is not JSON raises a message naming its number."""
    records = []
    with open(path, encoding="utf-8") as handle:
        for number, line in enumerate(handle, start=1):
            if not line.strip():
                continue
            try:
                records.append(json.loads(line))
            except json.JSONDecodeError as error:
                raise ValueError(f"{path}: line {number} is not a JSON record ({error.msg})") from None
    return records
