"""``teachbot study status``: who has done what, what is missing or aborted, and whether the orders are balanced."""

from __future__ import annotations

from dataclasses import dataclass

from dialog.study.design import assigned_orders, balance, williams_rows
from dialog.study.files import SessionState, session_state_of


@dataclass(frozen=True)
class Cell:
    participant: str
    position: int
    condition: str
    state: SessionState


def study_cells(study) -> list[Cell]:
    """One cell per participant and session position, with the state read from the files."""
    return [Cell(participant, position, name, session_state_of(study, participant, position, name))
            for participant, order in assigned_orders(study).items()
            for position, name in enumerate(order, start=1)]


def _shown(state: SessionState, turns: int) -> str:
    if state.state == "running":
        return f"running {state.turns_done}/{turns}"
    if state.state == "aborted":
        return "ABORTED"
    if state.state == "questionnaire":
        return "questionnaire due"
    if state.state == "damaged":
        return "DAMAGED"
    return state.state


def completed_orders(study, cells: list[Cell]) -> list[tuple[str, ...]]:
    """The orders of the participants who finished every session (aborted ones count as not finished)."""
    orders = assigned_orders(study)
    done = {}
    for cell in cells:
        done.setdefault(cell.participant, []).append(cell.state.state == "done")
    return [orders[participant] for participant, flags in done.items() if all(flags)]


def opening_lines(study) -> list[str]:
    """Consent and the practice round, one line each over the participants (nothing when the study has neither)."""
    from dialog.study.consent import consent_state

    lines = []
    if study.consent is not None:
        states = {participant: consent_state(study, participant) for participant in study.participants}
        lines.append(f"consent ({study.consent.file}): " + _tally(states))
    if study.practice is not None:
        states = {participant: _shown(session_state_of(study, participant, 0, "practice"), study.practice.turns)
                  for participant in study.participants}
        lines.append("practice round (not in the report's tables): " + _tally(states))
        for participant in study.participants:
            state = session_state_of(study, participant, 0, "practice")
            if state.state == "damaged":
                lines.append(f"damaged: {participant} practice round: {state.reason}")
    return lines


def _tally(states: dict[str, str]) -> str:
    """"P01 agreed, P02 agreed, P03 not asked yet" as "agreed: P01, P02; not asked yet: P03"."""
    groups: dict[str, list[str]] = {}
    for participant, state in states.items():
        groups.setdefault(state, []).append(participant)
    return "; ".join(f"{state}: {', '.join(names)}" for state, names in groups.items())


def status_text(study) -> str:
    """One line per participant ("dt-task: done" per session, in their order), then the counts and the balance."""
    cells = study_cells(study)
    names = [c.name for c in study.conditions]
    shown = {id(c): f"{c.condition}: {_shown(c.state, study.condition(c.condition).turns)}" for c in cells}
    width = max(len(text) for text in shown.values()) + 2 if shown else 12
    lines = [f"Study '{study.name}' ({study.path}), records in {study.folder}",
             "participant  " + "".join(f"{f'{p}.':<{width}}" for p in range(1, len(names) + 1)).rstrip()]
    by_participant: dict[str, list[Cell]] = {}
    for cell in cells:
        by_participant.setdefault(cell.participant, []).append(cell)
    for participant, row in by_participant.items():
        lines.append((f"{participant:<13}" + "".join(f"{shown[id(c)]:<{width}}" for c in row)).rstrip())
    lines += opening_lines(study)
    counts = {state: sum(c.state.state == state for c in cells) for state in
              ("done", "running", "questionnaire", "aborted", "damaged", "missing")}
    lines.append("sessions: " + ", ".join(f"{count} {state}" for state, count in counts.items()))
    for cell in cells:
        if cell.state.state == "aborted":
            lines.append(f"aborted: {cell.participant} session {cell.position} ({cell.condition}) after "
                         f"{cell.state.turns_done} turns: {cell.state.reason or 'no reason given'}")
        if cell.state.state == "damaged":
            lines.append(f"damaged: {cell.participant} session {cell.position} ({cell.condition}): {cell.state.reason}")
    finished = completed_orders(study, cells)
    result = balance(finished, names)
    block = len(williams_rows(len(names))) if study.ordering == "latin" else None
    verdict = "balanced" if result.balanced else (
        "positions balanced, carry-over not" if result.positions_balanced else "NOT balanced")
    note = f" (a complete block is a multiple of {block} participants)" if block else ""
    lines.append(f"orders of the {len(finished)} participants who finished every session: {verdict}{note}")
    if not result.positions_balanced:
        for name in names:
            counts = [result.positions[(name, p)] for p in range(1, len(names) + 1)]
            lines.append(f"  {name}: at positions 1..{len(names)}: " + ", ".join(str(c) for c in counts) + " times")
    return "\n".join(lines)
