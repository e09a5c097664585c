"""One reader per kind of study record, each checking every field against the study file.

A session's transcript, its questionnaire answers and its abort note are read
here and nowhere else. A damaged record is refused as ``FILE: line N: what is
wrong (expected ...)`` (a :class:`~learning.errors.TranscriptError`); ``study
status`` shows such a session as damaged, ``study report`` leaves it out of the
analysis and lists it, and ``study run`` refuses to write over it.
"""

from __future__ import annotations

import functools
import json
import math
import os
import re
from pathlib import Path

from bullet_world.features import environment_feature_catalogue, object_feature_catalogue, robot_feature_catalogue
from dialog.session import check_header
from dialog.transcripts.jsonl import read_numbered_session
from dialog.transcripts.records import TEXT_ACCEPTED, check_turn_record, text_problem
from learning.errors import TranscriptError

#: the session header fields a study's condition fixes, and where the condition keeps each
CONDITION_HEADER_FIELDS = ("task", "kitchen", "strategy", "turns", "budget", "change_every", "realtime")
STUDY_KEYS = ("study", "participant", "condition", "order")
STUDY_TABLE_KEYS = (*STUDY_KEYS, "software", "simulated")
#: a study session header's fields besides the ones :func:`expected_session` gives
HEADER_KEYS = {"format", "version", "study"}
SOFTWARE_PATTERN = re.compile(r"teachbot (?:[0-9][0-9A-Za-z.+!-]{0,63}|\(not installed\))")
#: what every turn record of a session has (``dialog.manager``: a turn is written whole, answer included)
TURN_FIELDS = ("time", "scene_id", "scene_check", "action", "answer", "cost", "budget_left", "model", "ended",
               "accuracy")
TEXT_LIMIT = 2000  # characters of a free-text answer (the terminal keeps no more)


def _shown(value) -> str:
    text = json.dumps(value, ensure_ascii=False, default=repr)
    text = text.encode("utf-8", "backslashreplace").decode("utf-8")  # a lone surrogate shown as \\ud800
    return text if len(text) <= 80 else f"{text[:80]}... ({len(text)} characters)"


def _feature_names() -> tuple[str, ...]:
    catalogue = object_feature_catalogue() + environment_feature_catalogue() + robot_feature_catalogue()
    return tuple(info.name for info in catalogue)


def expected_session(study, participant: str, order: int, condition) -> dict:
    """The header fields a session of ``condition`` must have been recorded with (its seed from the study seed),
    and under ``"teacher"`` the teacher table of a simulated participant (a person's is ``{"kind": "terminal"}``;
    which one applies is the record's own ``simulated`` flag)."""
    from dialog.study.design import session_seed

    fields = {name: getattr(condition, name) for name in CONDITION_HEADER_FIELDS}
    return fields | {"seed": session_seed(study, participant, condition.name), "command": "teach",
                     "costs": dict(condition.costs), "fetch_from_pantry": condition.fetch_from_pantry,
                     "concepts": list(_task_concepts(condition.task)), "features": len(_feature_names()),
                     "teacher": {"kind": "scripted", **study.simulated_teacher}}


@functools.cache
def _task_concepts(task: str) -> tuple[str, ...]:
    from bullet_world.catalogue import load_task

    return tuple(load_task(task).concepts)


def _check_study_table(path: Path, recorded, expected: dict, what: str, extra: tuple[str, ...] = ()) -> None:
    """The study table of a record's header: exactly the keys ``study run`` writes (``extra`` besides), naming this
    file's study, participant, condition and order, a teachbot version and whether it was a dry run."""
    if not isinstance(recorded, dict):
        raise TranscriptError(f"{path}: line 1: the {what} header has no study table (expected the study, participant, "
                              "condition and order, as teachbot study run writes them)")
    for key in STUDY_KEYS:
        if recorded.get(key) != expected[key]:
            raise TranscriptError(f"{path}: line 1: the header's study {key} is {_shown(recorded.get(key))} (expected "
                                  f"{_shown(expected[key])}, the {key} this file belongs to; was it moved, renamed or "
                                  "edited?)")
    software = recorded.get("software")
    if not (isinstance(software, str) and SOFTWARE_PATTERN.fullmatch(software)):
        raise TranscriptError(f"{path}: line 1: the header's study software is {_shown(software)} (expected the "
                              "version that recorded it, as teachbot --version prints it: 'teachbot 0.1.0')")
    if not isinstance(recorded.get("simulated"), bool):
        raise TranscriptError(f"{path}: line 1: the header's study simulated is {_shown(recorded.get('simulated'))} "
                              "(expected true for a dry run with --simulated, else false)")
    unknown = sorted(set(recorded) - set(STUDY_TABLE_KEYS) - set(extra), key=str)
    if unknown:
        raise TranscriptError(f"{path}: line 1: the header's study table has a field {_shown(unknown[0])} that study "
                              f"run does not write (expected only {', '.join(STUDY_TABLE_KEYS + extra)})")


def _same(recorded, value) -> bool:
    """A recorded header value equals the study file's (booleans are not numbers; numbers within 1e-12)."""
    if isinstance(value, bool) or isinstance(recorded, bool):
        return recorded is value
    if isinstance(value, (int, float)):
        return isinstance(recorded, (int, float)) and math.isclose(recorded, value, rel_tol=0, abs_tol=1e-12)
    if isinstance(value, dict):
        return isinstance(recorded, dict) and set(recorded) == set(value) and all(
            _same(recorded[key], value[key]) for key in value)
    if isinstance(value, list):
        return isinstance(recorded, list) and len(recorded) == len(value) and all(map(_same, recorded, value))
    return recorded == value


def _check_session_header(path: Path, header: dict, session: dict) -> None:
    """Every field of a study session's header: the ones the study file sets, the teacher the record's
    ``simulated`` flag implies, and no field ``study run`` does not write."""
    wanted = dict(session)
    if header["study"]["simulated"] is False:
        wanted["teacher"] = {"kind": "terminal"}
    allowed = set(wanted) | HEADER_KEYS | ({"policy"} if str(session["strategy"]).startswith("rl:") else set())
    unknown = sorted(set(header) - allowed, key=str)
    if unknown:
        raise TranscriptError(f"{path}: line 1: the session header has a field {_shown(unknown[0])} that study run "
                              "does not write (was it edited?)")
    for key, value in wanted.items():
        if not _same(header.get(key), value):
            raise TranscriptError(f"{path}: line 1: the session header's '{key}' is {_shown(header.get(key))} "
                                  f"(expected {_shown(value)}, as the study file sets it for this session)")
    try:
        check_header(header, path)  # what teach --resume checks too (a policy's SHA-256, ...)
    except TranscriptError as error:
        raise TranscriptError(str(error) if str(error).startswith(str(path)) else f"{path}: line 1: {error}") \
            from None


def read_study_transcript(path: Path, expected: dict, session: dict) -> tuple[dict, list[dict]]:
    """Header and turns of a session's transcript, every field checked; a torn last line (a crash) is left out.

    ``expected`` is the study table (:func:`dialog.study.files.study_header`), ``session`` the fields the
    condition fixes (:func:`expected_session`): a header that names another participant, condition, order,
    strategy, seed or number of turns, a duplicated or extra turn and a malformed field are refused by name.
    """
    _check_utf8(path)
    header, numbered = read_numbered_session(path, tolerate_partial_tail=True)
    if header is None:
        raise TranscriptError(f"{path}: line 1: no session header (expected the header teachbot study run writes)")
    _check_study_table(path, header.get("study"), expected, "session")
    _check_session_header(path, header, session)
    concepts = header["concepts"]
    names = _feature_names()
    records = []
    for turn, (line, record) in enumerate(numbered, start=1):
        try:
            check_turn_record(record, turn, session["turns"], concepts, names)
            missing = [name for name in TURN_FIELDS if name not in record]
            if missing:
                raise TranscriptError(f"the turn record has no '{missing[0]}' (expected every field study run "
                                      f"writes: {', '.join(TURN_FIELDS)})")
            accuracy = record.get("accuracy")
            if accuracy is not None and not (isinstance(accuracy, (int, float)) and not isinstance(accuracy, bool)
                                             and 0 <= accuracy <= 1):
                raise TranscriptError(f"'accuracy' is {_shown(accuracy)} (expected a held-out accuracy from 0 to 1)")
        except TranscriptError as error:
            raise TranscriptError(f"{path}: line {line}: {error}") from None
        records.append(record)
    return header, records


def torn_tail(path: Path) -> bool:
    """True when the transcript's last line has no newline (a crash mid-write, or a cut)."""
    with open(path, "rb") as handle:
        size = handle.seek(0, os.SEEK_END)
        if size == 0:
            return False
        handle.seek(size - 1)
        return handle.read(1) != b"\n"


def _regular(path: Path, what: str) -> None:
    """Refuse a record that is a folder, a FIFO or a device before opening it (reading a FIFO would block)."""
    if path.exists() and not path.is_file():
        raise TranscriptError(f"{path}: not a regular file (expected the {what} teachbot study run wrote)")


def _check_utf8(path: Path) -> None:
    """Refuse bytes that are not UTF-8 in the complete lines of a record (a torn last line is left to the resume)."""
    _regular(path, "transcript")
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise TranscriptError(f"{path}: cannot read the transcript ({error.strerror or error})") from None
    complete = raw[:raw.rfind(b"\n") + 1]
    try:
        complete.decode("utf-8")
    except UnicodeDecodeError as error:
        line = complete[:error.start].count(b"\n") + 1
        raise TranscriptError(f"{path}: line {line}: not UTF-8 text (byte {error.start}; expected the JSON Lines "
                              "teachbot writes)") from None


def _json_lines(path: Path, what: str) -> list[tuple[int, object]]:
    _regular(path, what)
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise TranscriptError(f"{path}: cannot read the {what} ({error.strerror or error})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        line = raw[:error.start].count(b"\n") + 1
        raise TranscriptError(f"{path}: line {line}: not UTF-8 text (byte {error.start}; expected the JSON Lines "
                              f"teachbot writes)") from None
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            rows.append((number, json.loads(line)))
        except json.JSONDecodeError as error:
            raise TranscriptError(f"{path}: line {number}: not a JSON record ({error.msg}; expected one JSON object "
                                  "per line)") from None
        except RecursionError:
            raise TranscriptError(f"{path}: line {number}: nests JSON too deeply (expected one flat record)") from None
    return rows


def read_questionnaire(path: Path, expected: dict, items) -> list[dict]:
    """The answers of a saved questionnaire, each checked: one line per item of the study, in its order, with a
    value the item accepts (a whole number 1..points or null; text or null), under a header naming this session."""
    rows = _json_lines(path, "questionnaire answers")
    if not rows or not isinstance(rows[0][1], dict) or set(rows[0][1]) != {"questionnaire"}:
        raise TranscriptError(f"{path}: line {rows[0][0] if rows else 1}: not a questionnaire header (expected "
                              "{\"questionnaire\": {study, participant, condition, order, software}})")
    _check_study_table(path, rows[0][1]["questionnaire"], expected, "questionnaire")
    by_id = {item.id: item for item in items}
    seen: dict[str, int] = {}
    answers = []
    for number, row in rows[1:]:
        where = f"{path}: line {number}"
        if not isinstance(row, dict) or set(row) != {"item", "kind", "value"}:
            raise TranscriptError(f"{where}: {_shown(row)} is not an answer (expected {{\"item\", \"kind\", "
                                  "\"value\"}})")
        item = by_id.get(row["item"]) if isinstance(row["item"], str) else None
        if item is None:
            raise TranscriptError(f"{where}: item {_shown(row['item'])} is not in the study's questionnaire "
                                  f"(expected one of {', '.join(by_id) or 'none'})")
        if row["item"] in seen:
            raise TranscriptError(f"{where}: item '{item.id}' is answered twice (first on line {seen[item.id]}; "
                                  "expected one answer per item)")
        seen[item.id] = number
        if row["kind"] != item.kind:
            raise TranscriptError(f"{where}: item '{item.id}' has kind {_shown(row['kind'])} (expected "
                                  f"'{item.kind}', as the study file says)")
        value = row["value"]
        if item.kind == "likert" and value is not None and not (
                isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= item.points):
            raise TranscriptError(f"{where}: item '{item.id}' has value {_shown(value)} (expected a whole number "
                                  f"from 1 to {item.points}, or null for skipped)")
        if item.kind == "text" and value is not None and not (isinstance(value, str) and len(value) <= TEXT_LIMIT):
            raise TranscriptError(f"{where}: item '{item.id}' has value {_shown(value)} (expected text of at most "
                                  f"{TEXT_LIMIT} characters, or null for left out)")
        if item.kind == "text" and isinstance(value, str) and text_problem(value):
            raise TranscriptError(f"{where}: item '{item.id}' has a value that is not text ({text_problem(value)}; "
                                  f"expected {TEXT_ACCEPTED}, or null for left out)")
        answers.append(row)
    missing = [item.id for item in items if item.id not in seen]
    if missing:
        raise TranscriptError(f"{path}: no answer for item '{missing[0]}' (expected one line for each of "
                              f"{', '.join(by_id)})")
    if [row["item"] for row in answers] != [item.id for item in items]:
        raise TranscriptError(f"{path}: the answers are not in the questionnaire's order (expected "
                              f"{', '.join(by_id)})")
    return answers


def read_abort_note(path: Path, expected: dict, turns: int) -> dict:
    """The note of an aborted session: its study table, a reason, the turns done before (0..turns)."""
    rows = _json_lines(path, "abort note")
    if len(rows) != 1 or not isinstance(rows[0][1], dict) or set(rows[0][1]) != {"aborted"} \
            or not isinstance(rows[0][1]["aborted"], dict):
        raise TranscriptError(f"{path}: line {rows[0][0] if rows else 1}: not an abort note (expected one line "
                              "{\"aborted\": {study, participant, condition, order, reason, after_turns, ...}})")
    note = rows[0][1]["aborted"]
    _check_study_table(path, note, expected, "abort note", extra=("reason", "after_turns", "state_before"))
    after = note.get("after_turns")
    if not (isinstance(after, int) and not isinstance(after, bool) and 0 <= after <= turns):
        raise TranscriptError(f"{path}: line 1: 'after_turns' is {_shown(after)} (expected a whole number from 0 to "
                              f"{turns}, the turns done before the abort)")
    if not (isinstance(note.get("reason"), str) and note["reason"].strip()):
        raise TranscriptError(f"{path}: line 1: 'reason' is {_shown(note.get('reason'))} (expected the reason given "
                              "with --abort)")
    return note
