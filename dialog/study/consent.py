"""Informed consent before anything is recorded: asked once per participant, recorded in their folder.

A study file may name a consent text (``consent = "consent.md"``, a file beside it). ``study run`` shows it
first, in the page or at the terminal. Agreeing writes ``<participant>/consent.json`` once::

    {"consent": {"study", "participant", "software", "simulated", "time", "text", "text_sha256", "given"}}

``given`` says how: ``"page"``, ``"terminal"``, or ``"simulated"`` (a dry run: nobody was asked, and the
record says so). Declining writes ``consent-declined.json`` (an earlier one is kept as ``*.superseded-N``)
and nothing else; the next run asks again. A consent record that can't be read, disagrees with the study
(another study, participant, or a text whose SHA-256 is not the consent file's now), or is missing while a
session of the participant is recorded, marks every session of the participant damaged
(:func:`consent_problem`), as any damaged record does.
"""

from __future__ import annotations

import json
import re
from datetime import datetime, timezone
from pathlib import Path

from dialog import software_version
from dialog.output_paths import superseded_name
from dialog.study.atomic import write_atomically
from dialog.study.records import SOFTWARE_PATTERN, _json_lines, _shown
from learning import datafiles as df
from learning.errors import TeachbotError, TranscriptError

CONSENT_FILE = "consent.json"
DECLINED_FILE = "consent-declined.json"
GIVEN = ("page", "terminal", "simulated")
FIELDS = ("study", "participant", "software", "simulated", "time", "text", "text_sha256", "given")
TIME_PATTERN = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(?:\.\d+)?(?:Z|[+-]\d\d:\d\d)")
SESSION_RECORD = re.compile(r"\d+-[A-Za-z0-9_][A-Za-z0-9._-]*\.jsonl")  # a participant's answers (an abort note
# is the researcher's: a participant may be marked aborted before they agreed)
QUESTION = "Do you agree to take part?"
AGREE, DECLINE = "I agree", "I do not agree"


def consent_path(study, participant: str) -> Path:
    folder = df.inside(study.folder, study.folder / participant, "participant's records")
    return folder / CONSENT_FILE


def _record(study, participant: str, given: str | None) -> dict:
    record = {"study": study.name, "participant": participant, "software": software_version(),
              "simulated": study.simulated, "time": datetime.now(timezone.utc).isoformat(timespec="seconds"),
              "text": study.consent.file, "text_sha256": study.consent.sha256}
    return record | ({"given": given} if given is not None else {})


def record_agreed(study, participant: str, given: str) -> Path:
    """Write the participant's consent once (never over a record: ``write_atomically(replace=False)``)."""
    path = consent_path(study, participant)
    write_atomically(path, json.dumps({"consent": _record(study, participant, given)}, ensure_ascii=False) + "\n",
                     "consent record", replace=False)
    return path


def record_declined(study, participant: str) -> Path:
    """The note that the participant declined: the only record such a run leaves (an earlier note is kept)."""
    path = consent_path(study, participant).with_name(DECLINED_FILE)
    if path.exists():
        path.rename(superseded_name(path))
    write_atomically(path, json.dumps({"declined": _record(study, participant, None)}, ensure_ascii=False) + "\n",
                     "consent declined note", replace=False)
    return path


def read_consent(path: Path, study, participant: str) -> dict:
    """The consent record, every field checked against the study file; a damaged one is a TranscriptError."""
    rows = _json_lines(path, "consent record")
    if len(rows) != 1 or not isinstance(rows[0][1], dict) or set(rows[0][1]) != {"consent"} \
            or not isinstance(rows[0][1]["consent"], dict):
        raise TranscriptError(f"{path}: line {rows[0][0] if rows else 1}: not a consent record (expected one line "
                              f"{{\"consent\": {{{', '.join(FIELDS)}}}}} as teachbot study run writes it)")
    record = rows[0][1]["consent"]
    where = f"{path}: line {rows[0][0]}"
    if set(record) != set(FIELDS):
        odd = sorted(set(record) ^ set(FIELDS), key=str)[0]
        raise TranscriptError(f"{where}: the consent record {'lacks' if odd in FIELDS else 'has a field'} "
                              f"{_shown(odd)} (expected exactly {', '.join(FIELDS)})")
    for key, wanted in (("study", study.name), ("participant", participant)):
        if record[key] != wanted:
            raise TranscriptError(f"{where}: the consent record's {key} is {_shown(record[key])} (expected "
                                  f"{_shown(wanted)}, the {key} this folder belongs to; was it moved or edited?)")
    if not (isinstance(record["software"], str) and SOFTWARE_PATTERN.fullmatch(record["software"])):
        raise TranscriptError(f"{where}: the consent record's software is {_shown(record['software'])} (expected "
                              "the version that recorded it, such as 'teachbot 0.1.0')")
    if record["given"] not in GIVEN or record["simulated"] is not (record["given"] == "simulated"):
        raise TranscriptError(f"{where}: the consent record's given/simulated are {_shown(record['given'])}/"
                              f"{_shown(record['simulated'])} (expected page/false, terminal/false or simulated/true)")
    if not (isinstance(record["time"], str) and TIME_PATTERN.fullmatch(record["time"])):
        raise TranscriptError(f"{where}: the consent record's time is {_shown(record['time'])} (expected an ISO "
                              "8601 time such as 2026-05-01T09:30:00+00:00)")
    if record["text"] != study.consent.file or record["text_sha256"] != study.consent.sha256:
        raise TranscriptError(f"{where}: the participant agreed to {_shown(record['text'])} with SHA-256 "
                              f"{_shown(record['text_sha256'])} (expected {study.consent.file}, SHA-256 "
                              f"{study.consent.sha256}, the consent text now; was the text edited after they "
                              "agreed? Restore it)")
    return record


def consent_problem(study, participant: str) -> str:
    """Why the participant's consent record is damaged ('' when it is fine, or the study asks no consent)."""
    if study.consent is None:
        return ""
    try:
        path = consent_path(study, participant)
        if path.exists() or path.is_symlink():
            read_consent(path, study, participant)
            return ""
        recorded = sorted(p.name for p in path.parent.iterdir() if SESSION_RECORD.fullmatch(p.name)) \
            if path.parent.is_dir() else []
    except (TeachbotError, PermissionError, IsADirectoryError, NotADirectoryError) as error:
        return str(error)
    if recorded:
        return (f"{path}: missing, but {recorded[0]} is recorded (consent is recorded before anything else; "
                "restore consent.json)")
    return ""


def consent_state(study, participant: str) -> str:
    """For study status: 'agreed', 'simulated', 'declined', 'not asked yet', 'DAMAGED', or '' (no consent)."""
    if study.consent is None:
        return ""
    if consent_problem(study, participant):
        return "DAMAGED"
    path = consent_path(study, participant)
    if path.exists():
        return "simulated" if read_consent(path, study, participant)["given"] == "simulated" else "agreed"
    return "declined" if path.with_name(DECLINED_FILE).exists() else "not asked yet"
