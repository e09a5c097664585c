"""Actions and answers as transcript fields, and back (for resume, replay and expert-mode tools).

A turn record holds the action (``{"kind": "label", "object": 4}`` with
objects numbered from 1, ``{"kind": "demo", "concept": "fruit"}``,
``{"kind": "feature"}``, ``{"kind": "none"}``) and the answer: its kind, the
raw lines the teacher typed, and the parsed value (a concept name, an object
number from 1, or a list of feature names).
"""

from __future__ import annotations

import numpy as np

from dialog.conversation import Outcome
from learning.actions import Action, DemoQuery, FeatureQuery, LabelQuery, NoQuery

ANSWER_KINDS = ("answer", "absent", "skip", "dont_know", "late", "none")


def action_record(action: Action) -> dict:
    record = {"kind": action.kind}
    if action.kind == "label":
        record["object"] = int(action.object_index) + 1
    elif action.kind == "demo":
        record["concept"] = action.concept
    return record


def action_from_record(record: dict) -> Action:
    """The action of a transcript record; a malformed one raises a message saying what is accepted."""
    kind = record.get("kind") if isinstance(record, dict) else None
    if kind == "label" and isinstance(record.get("object"), int) and record["object"] >= 1:
        return LabelQuery(record["object"] - 1)
    if kind == "demo" and isinstance(record.get("concept"), str):
        return DemoQuery(record["concept"])
    if kind == "feature":
        return FeatureQuery()
    if kind == "none":
        return NoQuery()
    raise ValueError(f"unreadable action {record!r}; accepted: {{'kind': 'label', 'object': N}}, "
                     "{'kind': 'demo', 'concept': NAME}, {'kind': 'feature'} or {'kind': 'none'}")


def _parsed(outcome: Outcome, action: Action, feature_names) -> object:
    if outcome.kind != "answer":
        return None
    if action.kind == "demo":
        return int(outcome.value) + 1
    if action.kind == "feature":
        return [feature_names[int(i)] for i in outcome.value]
    if isinstance(outcome.value, np.generic):
        return outcome.value.item()
    return outcome.value


def answer_record(outcome: Outcome, action: Action, feature_names) -> dict:
    record = {"kind": outcome.kind, "raw": outcome.raw, "parsed": _parsed(outcome, action, feature_names),
              "lines": list(outcome.lines), "seconds": round(float(outcome.seconds), 3)}
    if outcome.note:
        record["note"] = outcome.note
    return record


def outcome_from_record(record: dict, action: Action, feature_names) -> Outcome:
    """The outcome a turn record describes, checked against the session's concepts and features."""
    answer = record.get("answer") or {}
    kind = answer.get("kind", "answer" if answer.get("parsed") is not None else "skip")
    if action.kind == "none":
        return Outcome("none")
    if kind not in ANSWER_KINDS:
        raise ValueError(f"turn {record.get('turn')}: answer kind '{kind}' is not one of {', '.join(ANSWER_KINDS)}")
    parsed = answer.get("parsed")
    value = None
    if kind == "answer":
        if action.kind == "demo":
            value = int(parsed) - 1
        elif action.kind == "feature":
            unknown = [name for name in parsed if name not in feature_names]
            if unknown:
                raise ValueError(f"turn {record.get('turn')}: features {unknown} are not among this session's")
            value = tuple(feature_names.index(name) for name in parsed)
        else:
            value = parsed
    return Outcome(kind, value, list(answer.get("lines", [])), float(answer.get("seconds", 0.0)))
