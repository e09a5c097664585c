"""Where a study's records live and what state each session is in, read back from the files alone.

The practice round (a study's ``[practice]``) is the session at position 0 named ``practice``
(``0-practice.jsonl``), without a questionnaire; the consent record is ``dialog.study.consent``'s.

``<folder>/<participant>/<order>-<condition>.jsonl`` is the session's transcript (its header carries a
``study`` table: study, participant, condition, order, software version);
``<order>-<condition>-questionnaire.jsonl`` the answers to the questionnaire after it, and
``<order>-<condition>-aborted.json`` the note that the session was aborted, with its reason. A session
run again with ``--again`` keeps its old files, renamed ``*.superseded-N``. Recorded answers are never
written over: a questionnaire or a note is written only where none is (``write_atomically(...,
replace=False)``), and a session whose records disagree with each other or with the study file is
``damaged`` (``dialog.study.records`` reads each kind of record and says what is wrong).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from dialog import software_version
from dialog.output_paths import superseded_name, writing
from dialog.study.consent import consent_problem
from dialog.study.records import (
    expected_session,
    read_abort_note,
    read_questionnaire,
    read_study_transcript,
    torn_tail,
)
from learning import datafiles as df
from learning.errors import TeachbotError, TranscriptError

STATES = ("missing", "running", "questionnaire", "done", "aborted", "damaged")

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
        """The session's scene pictures: named by position only, since the participant sees their paths
        (``Picture: ...``) and nothing a participant sees may name the condition (docs/studies.md)."""
        return self.folder / f"{self.order}-pictures"

    def existing(self) -> list[Path]:
        return [path for path in (self.transcript, self.questionnaire, self.aborted) if path.exists()]


def session_files(study, participant: str, order: int, condition: str) -> SessionFiles:
    """The session's files, in ``<folder>/<participant>/``; a participant folder that leads out of the study's
    records folder (a symbolic link) is refused."""
    df.check_name(participant, "participant id", str(study.path))
    df.check_name(condition, "condition name", str(study.path))
    folder = df.inside(study.folder, study.folder / participant, "participant's records")
    return SessionFiles(folder, order, condition)


@dataclass(frozen=True)
class SessionState:
    state: str  # one of STATES
    turns_done: int = 0
    reason: str = ""  # why it was aborted, or what is damaged


def read_transcript_checked(files: SessionFiles, expected: dict, session: dict) -> tuple[dict, list[dict]]:
    """Header and turns of a session's transcript, every field checked (``dialog.study.records``)."""
    return read_study_transcript(files.transcript, expected, session)


def _has_content(path: Path) -> bool:
    """True for a transcript with something in it, and for anything that is not a regular file (the reader
    refuses it by name)."""
    return path.exists() and (not path.is_file() or path.stat().st_size > 0)


def session_state(files: SessionFiles, condition, expected: dict, session: dict, items) -> SessionState:
    """The state of one session from its files: missing, running (turns so far), questionnaire, done, aborted,
    or damaged (a record that can't be read, or that disagrees with the study file or with the other records)."""
    try:
        return _state(files, condition, expected, session, items)
    except (TeachbotError, OSError) as error:
        if isinstance(error, OSError) and not isinstance(error, (PermissionError, IsADirectoryError)):
            raise
        return SessionState("damaged", 0, str(error))


def _state(files: SessionFiles, condition, expected: dict, session: dict, items) -> SessionState:
    answered = files.questionnaire.exists()
    if answered:
        read_questionnaire(files.questionnaire, expected, items)
    if files.aborted.exists():
        note = read_abort_note(files.aborted, expected, condition.turns)
        return SessionState("aborted", note["after_turns"], note["reason"])
    if not _has_content(files.transcript):
        if answered:
            _refuse_unfinished(files, "is " + ("empty" if files.transcript.exists() else "missing"))
        return SessionState("missing")
    _, records = read_transcript_checked(files, expected, session)
    if answered and (len(records) < condition.turns or torn_tail(files.transcript)):
        # the questionnaire is asked only once the last turn is on disk: this transcript lost turns since
        torn = f", and line {len(records) + 2} is torn" if torn_tail(files.transcript) else ""
        _refuse_unfinished(files, f"ends after turn {len(records)} of {condition.turns}{torn}")
    if len(records) < condition.turns:
        return SessionState("running", len(records))
    if items and not answered:
        return SessionState("questionnaire", len(records))
    return SessionState("done", len(records))


def _refuse_unfinished(files: SessionFiles, how: str) -> None:
    raise TranscriptError(f"{files.transcript}: the transcript {how}, but the questionnaire after it is recorded in "
                          f"{files.questionnaire.name} (it is asked only once the whole session is on disk); restore "
                          f"the transcript, or run the condition again with --condition {files.condition} --again "
                          "(every record is kept, renamed *.superseded-N)")


def session_state_of(study, participant: str, position: int, name: str) -> SessionState:
    """:func:`session_state` of one participant's session at ``position`` (from 1) under condition ``name``."""
    condition = study.condition(name)
    try:
        files = session_files(study, participant, position, name)
    except TeachbotError as error:
        return SessionState("damaged", 0, str(error))
    problem = consent_problem(study, participant)
    if problem:  # a damaged or missing consent record: every record of the participant is in doubt
        return SessionState("damaged", 0, problem)
    items = () if position == 0 else study.items  # the practice round (position 0) has no questionnaire
    return session_state(files, condition, study_header(study, participant, name, position),
                         expected_session(study, participant, position, condition), items)


def supersede(files: SessionFiles) -> list[Path]:
    """Rename a session's files ``*.superseded-N`` (kept in the record) so that it can be run again."""
    moved = []
    for path in files.existing():
        target = superseded_name(path)
        with writing(path, "superseded session record"):
            path.rename(target)
        moved.append(target)
    return moved
