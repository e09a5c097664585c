"""What the page may send, checked before anything reaches the session (docs/web.md, "Messages").

Every message is one JSON object of at most ``MAX_MESSAGE_BYTES`` naming the
question it answers. Buttons, clicks and checkboxes become the line a person
would type at the terminal ("fruit", "number 4", "1.1, 1.2", "ignore 2"), so
the one grammar (``dialog/language/parsing.py``) reads every answer, whichever way it
came. A message that is malformed, forged (a concept the task lacks, an object
the scene lacks, a button the question has no use for) or stale (for an earlier
question) raises :class:`MessageError` and changes nothing.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from dialog.transcripts.records import text_problem
from learning.errors import MessageError

MAX_MESSAGE_BYTES = 4096
MAX_TYPED_CHARS = 1000  # the transcript keeps this many characters of a line (dialog/teachers/conversation.py)
COMMANDS = ("why", "undo", "skip", "quit", "help", "don't know", "none")
KINDS = {"typed": ("text",), "concept": ("concept",), "command": ("command",), "object": ("object",),
         "pick": ("object",), "click": ("x", "y"), "features": ("numbers", "mode")}
# "object": an object's number button; "pick": a click on it in the 3D view; "click": on the camera picture
COMMON = ("type", "question", "page_ms")


@dataclass(frozen=True)
class Asked:
    """What the open question accepts: its id, kind, concepts, object count, feature tree numbers."""

    question: int
    expects: str  # "label", "demo" or "feature"
    concepts: tuple[str, ...]
    n_objects: int
    tree_numbers: frozenset[str] = frozenset()


@dataclass(frozen=True)
class PageAnswer:
    """One accepted message: the line it stands for, how it came, and the page's answer time in seconds."""

    line: str
    channel: str
    page_seconds: float | None


def decode(raw: str | bytes) -> dict:
    """The message as a dict; an oversized, non-JSON or non-object message is refused."""
    size = len(raw.encode("utf-8") if isinstance(raw, str) else raw)
    if size > MAX_MESSAGE_BYTES:
        raise MessageError(f"a message of {size} bytes; accepted: at most {MAX_MESSAGE_BYTES} bytes")
    try:
        message = json.loads(raw)
    except (ValueError, UnicodeDecodeError):
        raise MessageError("a message that is not JSON; accepted: one JSON object such as "
                              '{"type": "concept", "question": 3, "concept": "fruit"}') from None
    except RecursionError:  # thousands of nested arrays fit in the size limit
        raise MessageError("a message that nests JSON too deeply; accepted: one flat JSON object such as "
                           '{"type": "concept", "question": 3, "concept": "fruit"}') from None
    if not isinstance(message, dict):
        raise MessageError(f"a JSON {type(message).__name__}; accepted: one JSON object with a type")
    return message


def read_message(message: dict, asked: Asked | None, resolve_click=None) -> PageAnswer:
    """The line ``message`` stands for, checked against the open question ``asked``.

    ``resolve_click(x, y)`` gives the 0-based object under a click on the camera picture, or None.
    """
    kind = message.get("type")
    if not isinstance(kind, str) or kind not in KINDS:
        raise MessageError(f"message type {_shown(kind)}; accepted: {', '.join(KINDS)}")
    unknown = sorted(set(message) - set(COMMON) - set(KINDS[kind]))
    if unknown:
        raise MessageError(f"unknown fields {', '.join(map(_shown, unknown))} in a {kind} message; accepted: "
                              f"{', '.join(COMMON + KINDS[kind])}")
    if asked is None:
        raise MessageError("an answer while no question is open; accepted: answers to the question shown")
    if not _is_whole(message.get("question")) or message.get("question") != asked.question:
        raise MessageError(f"an answer to question {_shown(message.get('question'))}; accepted: answers to the "
                              f"open question {asked.question}")
    page_ms = message.get("page_ms")
    if page_ms is not None and not (_is_number(page_ms) and 0 <= page_ms <= 86_400_000):
        raise MessageError(f"page_ms {_shown(page_ms)}; accepted: milliseconds from 0 to 86400000")
    seconds = None if page_ms is None else round(page_ms / 1000.0, 3)
    line, channel = _line(kind, message, asked, resolve_click)
    return PageAnswer(line, channel, seconds)


def _line(kind: str, message: dict, asked: Asked, resolve_click) -> tuple[str, str]:
    if kind == "typed":
        text = message.get("text")
        if not isinstance(text, str) or len(text) > MAX_TYPED_CHARS or _why(text, ""):
            raise MessageError(f"typed text {_shown(text)}{_why(text, '')}; accepted: one line of at most "
                               f"{MAX_TYPED_CHARS} characters, without control characters")
        return text, "typed"
    if kind == "command":
        command = message.get("command")
        allowed = COMMANDS if asked.expects == "demo" else tuple(c for c in COMMANDS if c != "none")
        if command not in allowed:
            raise MessageError(f"command {_shown(command)} for a {asked.expects} question; accepted: "
                                  f"{', '.join(allowed)}")
        return command, "button"
    if kind == "concept":
        concept = message.get("concept")
        if asked.expects != "label" or concept not in asked.concepts:
            raise MessageError(f"concept {_shown(concept)} for a {asked.expects} question; accepted: "
                                  f"{', '.join(asked.concepts) if asked.expects == 'label' else 'none here'}")
        return concept, "button"
    if kind in ("object", "pick", "click"):
        if asked.expects != "demo":
            raise MessageError(f"an object {kind} for a {asked.expects} question; accepted only when asked "
                                  "to show an object")
        if kind in ("object", "pick"):
            number = message.get("object")
            if not (_is_whole(number) and 1 <= number <= asked.n_objects):
                raise MessageError(f"object {_shown(number)}; accepted: 1 to {asked.n_objects}")
            return f"number {number}", "button" if kind == "object" else "click"
        x, y = message.get("x"), message.get("y")
        if not (_is_number(x) and _is_number(y) and 0 <= x <= 1 and 0 <= y <= 1):
            raise MessageError(f"a click at {_shown(x)}, {_shown(y)}; accepted: x and y from 0 to 1 across "
                                  "the picture")
        index = resolve_click(x, y) if resolve_click is not None else None
        if index is None:
            raise MessageError("a click on no object; accepted: a click on one of the numbered objects")
        return f"number {index + 1}", "click"
    numbers, mode = message.get("numbers"), message.get("mode")
    if asked.expects != "feature":
        raise MessageError(f"a feature choice for a {asked.expects} question; accepted only for the feature "
                              "question")
    if mode not in ("use", "ignore"):
        raise MessageError(f"feature mode {_shown(mode)}; accepted: use, ignore")
    if not (isinstance(numbers, list) and 1 <= len(numbers) <= len(asked.tree_numbers)
            and all(isinstance(n, str) and n in asked.tree_numbers for n in numbers)
            and len(set(numbers)) == len(numbers)):
        raise MessageError(f"feature numbers {_shown(numbers)}; accepted: a list of distinct numbers of the "
                              "feature tree shown")
    return ("ignore " if mode == "ignore" else "") + ", ".join(numbers), "button"


def _is_number(value) -> bool:
    """A JSON number that is finite (a whole number of any length is: math.isfinite would overflow on it)."""
    return _is_whole(value) or (isinstance(value, float) and math.isfinite(value))


def _is_whole(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _why(text, controls: str) -> str:
    """`` (what is wrong)`` with a text from the page that cannot be taken (records.text_problem), else ""."""
    problem = text_problem(text, controls) if isinstance(text, str) else ""
    return f" ({problem})" if problem else ""


def _shown(value) -> str:
    """``value`` as it came, in JSON, cut to 60 characters (nested too deeply to show: its type)."""
    try:
        text = json.dumps(value, ensure_ascii=False, default=str).encode("utf-8", "backslashreplace").decode("utf-8")
    except RecursionError:
        return f"(a JSON {type(value).__name__} nested too deeply to show)"
    return text if len(text) <= 60 else f"{text[:60]}... ({len(text)} characters)"


MAX_FREE_TEXT = 2000  # as at the terminal (dialog/study/questionnaire.py)
FREE_TEXT_CONTROLS = "\t\n\r"  # the control characters a text box may hold


def read_screen(message: dict, screen: dict | None) -> list:
    """The values a study screen's form gave (None: an item left out), checked against the open ``screen``."""
    choices = screen.get("choices") if screen is not None else None
    fields = {"type", "screen", "answers"} | ({"choice"} if choices else set())
    unknown = sorted(set(message) - fields)
    if unknown:
        raise MessageError(f"unknown fields {', '.join(map(_shown, unknown))} in a screen message; accepted: "
                           f"{', '.join(sorted(fields))}")
    if screen is None or not _is_whole(message.get("screen")) or message.get("screen") != screen["id"]:
        raise MessageError(f"an answer to screen {_shown(message.get('screen'))}; accepted: answers to the screen "
                           "shown")
    if choices:  # a screen answered by one of its buttons (the consent): that button's words, and no items
        if message.get("choice") not in choices or message.get("answers") != []:
            raise MessageError(f"screen choice {_shown(message.get('choice'))} with answers "
                               f"{_shown(message.get('answers'))}; accepted: one of {', '.join(choices)}, with "
                               "answers []")
        return [message["choice"]]
    items, answers = screen.get("items", []), message.get("answers")
    if not (isinstance(answers, list) and len(answers) == len(items) and all(isinstance(a, str) for a in answers)):
        raise MessageError(f"screen answers {_shown(answers)}; accepted: one text per item ({len(items)})")
    values = []
    for number, (item, answer) in enumerate(zip(items, answers), start=1):
        if item["kind"] == "likert":
            points = [str(point) for point in range(item["low"], item["high"] + 1)]
            if answer == "":
                values.append(None)
            elif answer in points:  # not str.isdigit: "²" is a digit that int() refuses
                values.append(int(answer))
            else:
                raise MessageError(f"item {number}: {_shown(answer)}; accepted: a whole number from {item['low']} "
                                   f"to {item['high']}, or none")
        elif len(answer) > MAX_FREE_TEXT:
            raise MessageError(f"item {number}: a text of {len(answer)} characters; accepted: at most {MAX_FREE_TEXT}")
        elif _why(answer, FREE_TEXT_CONTROLS):
            raise MessageError(f"item {number}: a text{_why(answer, FREE_TEXT_CONTROLS)}; accepted: plain "
                               "text (line breaks and tabs are fine)")
        else:
            values.append(answer.strip() or None)
    return values
