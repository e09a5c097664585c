"""Where a study's records live and what state each session is in, read back from the files alone.

``<folder>/<participant>/<order>-<condition>.jsonl`` is the session's transcript (its header carries a
``study`` table: study, participant, condition, order, software version);
``<order>-<condition>-questionnaire.jsonl`` the answers to the questionnaire after it, and
``<order>-<condition>-aborted.json`` the note that the session was aborted, with its reason. A session
run again with ``--again`` keeps its old files, renamed ``*.superseded-N``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from dialog import software_version
from dialog.output_paths import writing
from dialog.transcript import read_session
from learning.errors import TranscriptError

STATES = ("missing", "running", "questionnaire", "done", "aborted")


def study_header(study, participant: str, condition: str, order: int) -> dict:
    """What every record of a participant's session names: who, which condition, which position, which software."""
    return {"study": study.name, "participant": participant, "condition": condition, "order": order,
            "software": software_version(), "simulated": study.simulated}


@dataclass(frozen=True)
class SessionFiles:
    folder: Path
    order: int
    condition: str

    @property
    def stem(self) -> str:
        return f"{self.order}-{self.condition}"

    @property
    def transcript(self) -> Path:
        return self.folder / f"{self.stem}.jsonl"

    @property
    def questionnaire(self) -> Path:
        return self.folder / f"{self.stem}-questionnaire.jsonl"

    @property
    def aborted(self) -> Path:
        return self.folder / f"{self.stem}-aborted.json"

    @property
    def pictures(self) -> Path:
        return self.folder / f"{self.stem}-pictures"

    def existing(self) -> list[Path]:
        return [path for path in (self.transcript, self.questionnaire, self.aborted) if path.exists()]


def session_files(study, participant: str, order: int, condition: str) -> SessionFiles:
    return SessionFiles(study.folder / participant, order, condition)


@dataclass(frozen=True)
class SessionState:
    state: str  # one of STATES
    turns_done: int = 0
    reason: str = ""


def read_transcript_checked(files: SessionFiles, expected: dict) -> tuple[dict, list[dict]]:
    """Header and turns of a session's transcript; one whose study table names another session is refused."""
    header, records = read_session(files.transcript, tolerate_partial_tail=True)
    recorded = (header or {}).get("study")
    if not isinstance(recorded, dict):
        raise TranscriptError(f"{files.transcript}: line 1: the header has no study table; this file was not "
                              "written by teachbot study run")
    for key in ("study", "participant", "condition", "order"):
        if recorded.get(key) != expected[key]:
            raise TranscriptError(f"{files.transcript}: line 1: the header's study {key} is "
                                  f"{json.dumps(recorded.get(key))}, but this file belongs to {key} "
                                  f"{json.dumps(expected[key])}; was the file moved or renamed?")
    return header, records


def session_state(files: SessionFiles, turns: int, expected: dict, asks_questionnaire: bool) -> SessionState:
    """The state of one session from its files: missing, running (turns so far), questionnaire, done, aborted."""
    if files.aborted.exists():
        note = read_json_record(files.aborted, "aborted")
        return SessionState("aborted", int(note.get("after_turns", 0)), str(note.get("reason", "")))
    if not files.transcript.exists() or files.transcript.stat().st_size == 0:
        return SessionState("missing")
    _, records = read_transcript_checked(files, expected)
    if len(records) < turns:
        return SessionState("running", len(records))
    if asks_questionnaire and not files.questionnaire.exists():
        return SessionState("questionnaire", len(records))
    return SessionState("done", len(records))


def read_json_record(path: Path, key: str) -> dict:
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as error:
        raise TranscriptError(f"{path}: cannot read the study record ({error})") from None
    if not isinstance(record, dict) or not isinstance(record.get(key), dict):
        raise TranscriptError(f"{path}: not a teachbot study record (no '{key}' table)")
    return record[key]


def write_atomically(path: Path, text: str, what: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename: the record is there whole or not at all."""
    temporary = path.with_name(f".{path.name}.tmp")
    with writing(path, what):
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(temporary, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)


def supersede(files: SessionFiles) -> list[Path]:
    """Rename a session's files ``*.superseded-N`` (kept in the record) so that it can be run again."""
    moved = []
    for path in files.existing():
        number = 1
        while path.with_name(f"{path.name}.superseded-{number}").exists():
            number += 1
        target = path.with_name(f"{path.name}.superseded-{number}")
        with writing(path, "superseded session record"):
            path.rename(target)
        moved.append(target)
    return moved
