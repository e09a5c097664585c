"""One question and its answer: ask, read, explain, confirm, ask again (nothing is guessed).

``converse`` shows the prompt, reads the teacher's lines and returns an
:class:`Outcome`. "help" and "why" are answered in place; an unreadable line is
refused with the accepted forms and the question stays open; close candidates
are confirmed first. Commands that end the question ("skip", "don't know",
"undo", "quit") come back as the outcome's kind for the manager to act on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, get_args

from dialog.language.parsing import AnswerParser, Reading
from dialog.language.questions import Prompt, help_text
from dialog.teachers.protocol import ReportsChannels, Teacher

MAX_RECORDED_CHARS = 1000   # a raw line is cut to this length in the transcript
MAX_LINES_PER_QUESTION = 200  # then the question counts as skipped (a teacher that only sends noise)

OutcomeKind = Literal["answer", "absent", "skip", "dont_know", "undo", "quit", "late", "none"]
OUTCOME_KINDS: tuple[OutcomeKind, ...] = get_args(OutcomeKind)


@dataclass
class Outcome:
    """How a question ended.

    kind: "answer" (``value``: concept name, object index, or tuple of feature
    indices), "absent" (no example here), "skip", "dont_know", "undo", "quit",
    "late" (answered after the deadline, or not at all), or "none" (no question).
    """

    kind: OutcomeKind
    value: object = None
    lines: list[str] = field(default_factory=list)
    seconds: float = 0.0
    note: str = ""
    channels: list[dict] = field(default_factory=list)  # per line, from a teacher that reports them (the page)

    @property
    def raw(self) -> str:
        return self.lines[-1] if self.lines else ""


def read_line(prompt: Prompt, parser: AnswerParser, line: str) -> Reading:
    """Read one line as an answer to ``prompt``."""
    if prompt.expects == "label":
        return parser.label(line)
    if prompt.expects == "demo":
        return parser.demonstration(line, prompt.scene.n_objects, prompt.action.concept)
    return prompt.feature_tree.read(line, parser.vocabulary)


def converse(teacher: Teacher, prompt: Prompt, parser: AnswerParser, clock) -> Outcome:
    """Ask ``prompt`` until it is answered, declined, or time runs out."""
    started = clock.now()
    teacher.show(prompt)
    lines: list[str] = []
    channels: list[dict] = []
    reports = isinstance(teacher, ReportsChannels)
    choices: tuple = ()
    while True:
        line = teacher.listen(prompt, prompt.deadline)
        now = clock.now()
        late = prompt.deadline is not None and now > prompt.deadline
        if line is None:
            return Outcome("late" if late or (prompt.deadline is not None and now >= prompt.deadline) else "quit",
                           None, lines, now - started, "" if prompt.deadline is not None else "end of input",
                           channels)
        lines.append(line[:MAX_RECORDED_CHARS])
        if reports:
            channels.append(teacher.answer_channel())
        if late:
            return Outcome("late", None, lines, now - started, channels=channels)
        reading = parser.choice(line, choices) if choices else read_line(prompt, parser, line)
        if len(lines) >= MAX_LINES_PER_QUESTION and reading.kind in ("help", "why", "more", "unreadable", "reject",
                                                                    "choose"):
            teacher.tell(f"({len(lines)} answers without one I could take: I'll skip this question.)")
            return Outcome("skip", None, lines, clock.now() - started, "too many unreadable answers", channels)
        if reading.kind == "more":  # a group of the feature list opened: a reply, the question stays open
            teacher.tell(reading.message)
        elif reading.kind == "help":
            teacher.tell(getattr(teacher, "help_for", help_text)(prompt) if not choices else
                         "Type the number of the one you meant, or 'no' to answer the question again.")
        elif reading.kind == "why":
            teacher.tell(f"Why I ask: {prompt.explanation}" if prompt.explanation else "I have no reason to give.")
        elif reading.kind == "unreadable":
            teacher.tell(reading.message)
        elif reading.kind == "reject":
            choices = ()
            teacher.tell(f"All right. {prompt.text}")
        elif reading.kind == "choose":
            choices = reading.choices
            options = " or ".join(f"{i + 1} {c}" for i, c in enumerate(choices))
            question = f"Did you mean {choices[0]}? (yes or no)" if len(choices) == 1 else f"Did you mean {options}?"
            teacher.tell(f"{reading.message} {question}".strip())
        else:
            note = reading.message if reading.kind == "answer" else ""
            if note.startswith("("):  # a typo read as a concept: say so, so that the teacher can undo it
                teacher.tell(note)
            return Outcome(reading.kind, reading.value, lines, clock.now() - started, note, channels)
