"""The questionnaire after a session: asked at the terminal (or answered by a simulated participant), then saved.

A Likert item takes a whole number from 1 to its number of points (``skip``
leaves it unanswered); a free-text item takes any line of Unicode text (empty:
unanswered); a line that is not text (a lone surrogate such as ``"\\ud800"``,
which no file can hold as UTF-8) is refused where it is typed, and asked again.
The answers are written together, once all are given, as JSON Lines: a
``questionnaire`` header (who, which condition, which position, which software)
and one line per item; never over answers already recorded. They are read
back by ``dialog.study.records.read_questionnaire``.
"""

from __future__ import annotations

import json

from dialog.study.atomic import write_atomically
from dialog.transcripts.records import TEXT_ACCEPTED, text_problem

SKIP_WORDS = ("skip", "pass", "-")


def likert_value(line: str, points: int) -> tuple[bool, int | None]:
    """(accepted, value) for one typed line: a number 1..points, or a skip word (value None)."""
    text = line.strip().lower()
    if text in SKIP_WORDS:
        return True, None
    if text.isdigit() and 1 <= int(text) <= points:
        return True, int(text)
    return False, None


def ask_terminal(items, read_line, write) -> list[dict] | None:
    """Each item's answer from a person; None when the input ended before the last one (nothing is saved)."""
    answers = []
    write(f"\nA few questions about this session ({len(items)}). Type 'skip' to leave one out.")
    for number, item in enumerate(items, start=1):
        if item.kind == "likert":
            write(f"\n{number}. {item.text}\n   1 = {item.anchors[0]} ... {item.points} = {item.anchors[1]}")
            while True:
                write("> ", end="")
                line = read_line()
                if line is None:
                    return None
                accepted, value = likert_value(line, item.points)
                if accepted:
                    break
                write(f"   Please type a whole number from 1 to {item.points}, or 'skip'.")
        else:
            write(f"\n{number}. {item.text}\n   (any text; Enter alone leaves it out)")
            while True:
                write("> ", end="")
                line = read_line()
                if line is None:
                    return None
                problem = text_problem(line)
                if not problem:
                    break
                write(f"   That text can't be recorded ({problem}). Please type {TEXT_ACCEPTED}, or Enter alone "
                      "to leave it out.")
            value = line.strip()[:2000] or None
        answers.append({"item": item.id, "kind": item.kind, "value": value})
    return answers


def ask_web(items, teacher) -> list[dict]:
    """Each item's answer from the page's form (``dialog.web.teacher.WebTeacher.ask_screen``): Likert items as
    radio buttons, free text as a text box; an item left empty is left out. A text that is not Unicode text
    brings the form back with the reason (``text_problem``)."""
    shown = [{"kind": "likert", "text": item.text, "low": 1, "high": item.points, "low_label": item.anchors[0],
              "high_label": item.anchors[1]} if item.kind == "likert" else {"kind": "text", "text": item.text}
             for item in items]
    note = "Leave an item empty to leave it out."
    while True:
        values = teacher.ask_screen("A few questions about this session", note, "Save the answers", shown)
        problems = [f"item {number}: {text_problem(value)}" for number, value in enumerate(values, start=1)
                    if isinstance(value, str) and text_problem(value)]
        if not problems:
            return [{"item": item.id, "kind": item.kind, "value": value} for item, value in zip(items, values)]
        note = (f"Those answers can't be recorded ({'; '.join(problems)}). Please give {TEXT_ACCEPTED}, or leave "
                "an item empty to leave it out.")


def ask_simulated(items, rng) -> list[dict]:
    """A simulated participant's answers: Likert values around the middle of the scale, a fixed free text."""
    answers = []
    for item in items:
        if item.kind == "likert":
            middle = (item.points + 1) / 2
            value = int(min(item.points, max(1, round(rng.normal(middle, item.points / 5)))))
        else:
            value = "(simulated participant)"
        answers.append({"item": item.id, "kind": item.kind, "value": value})
    return answers


def save(path, header: dict, answers: list[dict]) -> None:
    """Write the answers once: a file that already holds answers is never replaced (``OutputPathError``)."""
    lines = [json.dumps({"questionnaire": header}, ensure_ascii=False)]
    lines += [json.dumps(answer, ensure_ascii=False) for answer in answers]
    write_atomically(path, "\n".join(lines) + "\n", "questionnaire answers", replace=False)
