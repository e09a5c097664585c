"""Hostile page messages for ``fuzz_web.py``: each breaks one stated rule of ``dialog/web/messages.py``, so each must
get exactly one refusal (or, over the websocket's limit, close the socket). Seeded: the same generator, the same
messages."""

from __future__ import annotations

import json

import numpy as np

from dialog.web.messages import KINDS, MAX_MESSAGE_BYTES
from dialog.web.server import WEBSOCKET_LIMIT_BYTES

HUGE = int("9" * 401)
# lone surrogates (no UTF-8 exists for them) and control characters: what no text field may hold
POISON = ["\ud800", "\udfff", "a\udc80b", "\x00", "\x07", "\x1b[2J", "\x7f", "\x85", "\x9b", "\x0b", "\x1f"]
WRONG_TYPES = [[], {}, [["x"]], {"a": 1}, True, 1.5, "word"]
NON_FINITE = ["Infinity", "-Infinity", "NaN", "1e309", "-1e309"]  # JSON literals Python's decoder takes


def deep(depth: int, inner: str = "1") -> str:
    return "[" * depth + inner + "]" * depth


class Hostile:
    """Hostile messages for an open question (``question``: the page's dict) or study screen (``screen``)."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng

    def pick(self, options):
        return options[int(self.rng.integers(len(options)))]

    def poisoned(self, text: str = "fruit") -> str:
        at = int(self.rng.integers(len(text) + 1))
        return text[:at] + self.pick(POISON) + text[at:]

    def base(self, question: dict) -> dict:
        """A valid answer to ``question``, the start of every mutation (exactly one defect is added)."""
        ident = question["id"]
        kind = self.pick(["typed", "command", "concept", "object", "click", "features"])
        if kind == "typed":
            return {"type": "typed", "question": ident, "text": "fruit", "page_ms": 1200}
        if kind == "command" or question["expects"] == "feature" and kind == "concept":
            return {"type": "command", "question": ident, "command": "why", "page_ms": 900}
        if kind == "concept" and question["expects"] == "label":
            return {"type": "concept", "question": ident, "concept": self.pick(question["concepts"])}
        if kind in ("object", "click") and question["expects"] == "demo":
            return ({"type": "object", "question": ident, "object": 1} if kind == "object"
                    else {"type": "click", "question": ident, "x": 0.5, "y": 0.5})
        if kind == "features" and question["expects"] == "feature" and question["features"]:
            return {"type": "features", "question": ident, "numbers": [question["features"][0]["number"]],
                    "mode": "use"}
        return {"type": "typed", "question": ident, "text": "snack"}

    def for_question(self, question: dict) -> tuple[str, str | bytes]:
        """(category, raw message) with one defect against the open ``question``."""
        message = self.base(question)
        category = self.pick(["json", "type", "numbers", "nesting", "text", "ids", "fields", "size"])
        return category, getattr(self, f"_{category}")(message, question)

    def for_screen(self, screen: dict) -> tuple[str, str | bytes]:
        """(category, raw message) with one defect against the open study ``screen``."""
        items = screen.get("items", [])
        answers = ["3" if item["kind"] == "likert" else "fine" for item in items]
        message = {"type": "screen", "screen": screen["id"], "answers": answers}
        choices = screen.get("choices") or []
        if choices:  # a screen answered by one of its buttons (the consent): the button's words, no items
            message["choice"] = choices[0]
            if self.rng.random() < 0.4:
                message["choice"] = self.pick([None, 1, "", choices[0].upper(), choices[0] + " ", [choices[0]],
                                               {"choice": choices[0]}, self.poisoned(choices[0]), "yes"])
                return "screen choice", json.dumps(message)
        elif self.rng.random() < 0.1:  # a choice for a screen that has none
            message["choice"] = self.pick(["I agree", "", None])
            return "screen choice", json.dumps(message)
        texts = [i for i, item in enumerate(items) if item["kind"] != "likert"]
        scales = [i for i, item in enumerate(items) if item["kind"] == "likert"]
        choice = int(self.rng.integers(8))
        if choice == 0 and texts:  # free text may hold line breaks and tabs, nothing else of its kind
            index = self.pick(texts)
            message["answers"][index] = self.poisoned("fine")
            return "screen text", json.dumps(message)
        if choice == 1 and scales:
            index = self.pick(scales)
            message["answers"][index] = self.pick(["\u00b2", "\u0663", "0", "99", " 3", "3.0", "-1", "1e1",
                                                   self.poisoned("3")])
            return "screen scale", json.dumps(message)
        if choice == 2:
            message["screen"] = self.pick([screen["id"] + 1, screen["id"] - 1, float(screen["id"]),
                                           str(screen["id"]), True, None, HUGE])
            return "screen id", json.dumps(message)
        if choice == 3:
            wrong = [answers + ["x"], None, "3", {"0": "3"}]
            if answers:  # (an empty list is right for a screen without items)
                wrong += [answers[:-1], [1] * len(answers), [[a] for a in answers], [None] * len(answers)]
            message["answers"] = self.pick(wrong)
            return "screen answers", json.dumps(message)
        if choice == 4:
            return "nesting", json.dumps(message).replace('"answers": [', f'"answers": [{deep(1500)}, ', 1)
        if choice == 5:
            message[self.pick(["extra", "question", self.poisoned("x")])] = 1
            return "fields", json.dumps(message)
        if choice == 6:
            return "json", self._json(message, None)
        return "ids", json.dumps({"type": "concept", "question": screen["id"], "concept": "fruit"})

    # -- one defect each -------------------------------------------------------------------------------
    def _json(self, message: dict, question) -> str | bytes:
        text = json.dumps(message)
        return self.pick([text[: int(self.rng.integers(1, len(text)))], "", "{", "}", "null", "[]", "42", '"typed"',
                          text + "x", text.replace('"', "'"), text.replace(":", "=", 1), "\x00" + text,
                          text.encode("utf-8") + b"\xff", b"\xc3\x28" + text.encode(), json.dumps([message]),
                          text.replace('"typed"', '"ty\x00ped"').replace('"', '"\x01', 1)])

    def _type(self, message: dict, question) -> str:
        message["type"] = self.pick([*WRONG_TYPES, None, 3, "", "TYPED", "answer", "screen ", self.poisoned("typed"),
                                     [message["type"]], {message["type"]: 1}])
        return json.dumps(message)

    def _numbers(self, message: dict, question) -> str:
        field = self.pick(["page_ms", "page_ms", "question"] + (["x", "y"] if message["type"] == "click" else [])
                          + (["object"] if message["type"] == "object" else []))
        value = self.pick([HUGE, -HUGE, "NONFINITE", -1, 86_400_001, 2**64, 1e300, -0.5])
        if field in ("x", "y"):
            value = self.pick([HUGE, -HUGE, "NONFINITE", 1.0000001, -1e-9, 2])
        if field == "object":
            value = self.pick([HUGE, -HUGE, "NONFINITE", 0, -1, question.get("objects", 0) + 1, 1.0, 1.5])
        if field == "question":
            value = self.pick([HUGE, -HUGE, "NONFINITE"])
        message[field] = value
        text = json.dumps(message)
        return text.replace('"NONFINITE"', self.pick(NON_FINITE))

    def _nesting(self, message: dict, question) -> str:
        field = self.pick([key for key in message if key != "type"] + ["type"])
        depth = int(self.pick([1100, 1500, 2000, 3000]))
        inner = self.pick(["1", '"fruit"', "{}", "[]"])
        text = json.dumps({**message, field: "NESTED"}).replace('"NESTED"', deep(depth, inner))
        return text if self.rng.random() < 0.8 else deep(depth)

    def _text(self, message: dict, question) -> str:
        """A lone surrogate or control character in every kind of text field, keys too."""
        if message["type"] == "typed" or self.rng.random() < 0.3:
            message = {"type": "typed", "question": message["question"], "text": self.poisoned(self.pick(
                ["fruit", "a snack", "number 3", "why", "", "1.1, 2", "don't know"]))}
        elif message["type"] == "features":
            message[self.pick(["mode", "numbers"])] = self.poisoned("use") if self.rng.random() < 0.5 else \
                [self.poisoned(message["numbers"][0])]
        else:
            field = {"command": "command", "concept": "concept", "object": "type", "click": "type"}[message["type"]]
            if self.rng.random() < 0.2:
                message[self.poisoned("note")] = "x"  # a key, not a value
            else:
                message[field] = self.poisoned(str(message[field]))
        return json.dumps(message)  # ASCII escapes: valid JSON, the surrogate intact

    def _ids(self, message: dict, question) -> str:
        ident = message["question"]
        message["question"] = self.pick([ident - 1, ident + 1, ident + 1000, 0, -ident, float(ident), str(ident),
                                         True, False, None, [ident], {"id": ident}])
        return json.dumps(message)

    def _fields(self, message: dict, question) -> str:
        extra = self.pick(["as", "__proto__", "constructor", "screen", "answers", "text", "concept", "object"])
        if extra in message or extra in KINDS.get(message["type"], ()):
            extra = "extra"
        message[extra] = self.pick(["admin", 1, None, [], {}])
        if self.rng.random() < 0.3:
            message.pop(self.pick([key for key in message if key not in ("type", extra)] or ["type"]), None)
            message["extra"] = 1
        return json.dumps(message)

    def _size(self, message: dict, question) -> str:
        padding = int(self.rng.integers(MAX_MESSAGE_BYTES + 1, 3 * MAX_MESSAGE_BYTES))
        return json.dumps({**message, "pad": "x" * padding})


def oversized(question_id: int) -> str:
    """A message over the websocket's limit: the server closes the socket (no refusal comes)."""
    return json.dumps({"type": "typed", "question": question_id, "text": "x" * (WEBSOCKET_LIMIT_BYTES + 10)})
