"""The study's records as tidy tables: one row per recorded turn, one per questionnaire answer.

Every session that has a transcript contributes its turns, finished or not
(``state`` says which), except a damaged one (its records are not read); the
analysis uses the finished ones.
"""

from __future__ import annotations

from dataclasses import dataclass

from dialog.study.files import read_transcript_checked, session_files, study_header
from dialog.study.records import expected_session, read_questionnaire
from dialog.study.status import Cell, study_cells

TURN_COLUMNS = ("participant", "condition", "order", "simulated", "state", "turn", "action", "cost", "answer",
                "answer_seconds", "refused", "accuracy", "channel", "page_seconds")
ANSWER_COLUMNS = ("participant", "condition", "order", "simulated", "item", "kind", "value")
COMMAND_WORDS = frozenset({"help", "?", "why", "more", "undo"})  # lines that ask something rather than answer


def refused_attempts(answer: dict) -> int:
    """Lines typed before the one taken that were answers the robot could not take (help, why, undo not counted)."""
    lines = list(answer.get("lines") or [])
    taken = 1 if answer.get("kind") in ("answer", "absent", "skip", "dont_know") and lines else 0
    return sum(line.strip().lower() not in COMMAND_WORDS for line in lines[:len(lines) - taken])


def recorded_as_simulated(study_table: dict, written_before: bool) -> bool:
    """Whether a record's study table says a scripted teacher played the participant; ``written_before`` answers
    for records written before the table had the field."""
    return bool(study_table.get("simulated", written_before))


def answer_channel(answer: dict) -> dict:
    """How the line taken came in a page's session (click, button, typed) and the page's seconds to it; empty for
    a terminal session."""
    channels, times = answer.get("channels") or [], answer.get("page_seconds") or []
    if not channels:
        return {"channel": None, "page_seconds": None}
    return {"channel": channels[-1], "page_seconds": times[-1] if times else None}


@dataclass
class StudyTables:
    cells: list[Cell]
    turns: list[dict]
    answers: list[dict]

    def simulated_sessions(self) -> tuple[int, int]:
        """(simulated, real): the sessions with a record that says it was simulated, and those with one that says
        it was not (a session whose transcript and questionnaire disagree counts in both)."""
        sessions = {flag: {(row["participant"], row["condition"]) for row in self.turns + self.answers
                           if row["simulated"] == flag} for flag in (True, False)}
        return len(sessions[True]), len(sessions[False])


def collect(study) -> StudyTables:
    cells = study_cells(study)
    turns, answers = [], []
    for cell in cells:
        if cell.state.state == "damaged":
            continue  # listed in the report with what is wrong; its records are not read
        files = session_files(study, cell.participant, cell.position, cell.condition)
        key = {"participant": cell.participant, "condition": cell.condition, "order": cell.position}
        expected = study_header(study, cell.participant, cell.condition, cell.position)
        if files.transcript.exists() and files.transcript.stat().st_size > 0:
            session = expected_session(study, cell.participant, cell.position, study.condition(cell.condition))
            header, records = read_transcript_checked(files, expected, session)
            scripted = (header.get("teacher") or {}).get("kind") == "scripted"
            simulated = recorded_as_simulated(header.get("study", {}), scripted)
            for record in records:
                answer = record.get("answer") or {}
                turns.append({**key, "simulated": simulated, "state": cell.state.state, "turn": record["turn"],
                              "action": record["action"]["kind"], "cost": record.get("cost", 0.0),
                              "answer": answer.get("kind", "none"), "answer_seconds": answer.get("seconds", 0.0),
                              "refused": refused_attempts(answer), "accuracy": record.get("accuracy"),
                              **answer_channel(answer)})
        if files.questionnaire.exists():
            simulated = any(t["simulated"] for t in turns  # written by the same run as the session's transcript
                            if t["participant"] == cell.participant and t["condition"] == cell.condition)
            for row in read_questionnaire(files.questionnaire, expected, study.items):
                answers.append({**key, "simulated": simulated, "item": row["item"], "kind": row["kind"],
                                "value": row["value"]})
    return StudyTables(cells, turns, answers)


def write_csv(path, columns, rows) -> None:
    import csv
    import io

    from dialog.study.atomic import write_atomically

    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({column: "" if row.get(column) is None else row.get(column) for column in columns})
    write_atomically(path, buffer.getvalue(), "study table")
