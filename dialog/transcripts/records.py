"""Actions and answers as transcript fields, and back (for resume, replay and expert-mode tools).

A turn record holds the action (``{"kind": "label", "object": 4}`` with
objects numbered from 1, ``{"kind": "demo", "concept": "fruit"}``,
``{"kind": "feature"}``, ``{"kind": "none"}``) and the answer: its kind, the
raw lines the teacher typed, and the parsed value (a concept name, an object
number from 1, or a list of feature names).
"""

from __future__ import annotations

import json
import math
import unicodedata

import numpy as np

from dialog.language.describe import OLD_WORLD_VIEWPOINT, SceneDescriber
from dialog.language.questions import question_text
from dialog.teachers.conversation import Outcome
from learning.actions import Action, DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.errors import TranscriptError

ANSWER_KINDS = ("answer", "absent", "skip", "dont_know", "late", "none")
CHANNELS = ("typed", "button", "click")  # how a page's answer line came (dialog/web/messages.py makes them)
TEXT_ACCEPTED = "any Unicode text (letters, digits, punctuation, emoji)"


def text_problem(text: str, controls: str | None = None) -> str:
    """Why typed text can't be recorded ('' when it can): a lone surrogate (``"\\ud800"``, which a JSON
    escape or a page can carry) is no Unicode character, and no UTF-8 file can hold it. With ``controls``, a
    control character other than those is refused too (the page's one-line and free-text fields)."""
    for position, ch in enumerate(text, start=1):
        category = unicodedata.category(ch)
        if category == "Cs":
            return (f"character {position} is U+{ord(ch):04X}, half of a surrogate pair, which is not a "
                    "character of its own")
        if controls is not None and category == "Cc" and ch not in controls:
            return f"character {position} is U+{ord(ch):04X}, a control character"
    return ""


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
    raise TranscriptError(f"unreadable action {record!r}; accepted: {{'kind': 'label', 'object': N}}, "
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
    if outcome.channels:  # only a page's answers say how each line came (terminal transcripts stay as they were)
        record["channels"] = [entry["channel"] for entry in outcome.channels]
        record["page_seconds"] = [entry.get("page_seconds") for entry in outcome.channels]
    return record


def outcome_from_record(record: dict, action: Action, feature_names) -> Outcome:
    """The outcome a turn record describes, checked against the session's concepts and features."""
    answer = record.get("answer") or {}
    kind = answer.get("kind", "answer" if answer.get("parsed") is not None else "skip")
    if action.kind == "none":
        return Outcome("none")
    if kind not in ANSWER_KINDS:
        raise TranscriptError(f"turn {record.get('turn')}: answer kind '{kind}' is not one of "
                              f"{', '.join(ANSWER_KINDS)}")
    parsed = answer.get("parsed")
    value = None
    if kind == "answer":
        if action.kind == "demo":
            value = int(parsed) - 1
        elif action.kind == "feature":
            unknown = [name for name in parsed if name not in feature_names]
            if unknown:
                raise TranscriptError(f"turn {record.get('turn')}: features {unknown} are not among this session's")
            value = tuple(feature_names.index(name) for name in parsed)
        else:
            value = parsed
    return Outcome(kind, value, list(answer.get("lines", [])), float(answer.get("seconds", 0.0)))


def read_replay_records(path) -> list[dict]:
    """The turn records a replay teacher answers from (``teach --teacher replay --replay FILE``): the file passes
    the checks every transcript read does (a regular file, not too large, JSON Lines), and each record has a
    turn number, once, and typed lines; anything else is refused as ``FILE: line N: ... (expected ...)``."""
    from dialog.transcripts.jsonl import read_numbered_session

    _, numbered = read_numbered_session(path)
    seen: set[int] = set()
    for line, record in numbered:
        try:
            turn, answer = record.get("turn"), record.get("answer", {})
            if not _is_int(turn) or turn < 1 or turn in seen:
                raise _refuse("turn", turn, "a whole number from 1, once per turn")
            seen.add(turn)
            if not isinstance(answer, dict):
                raise _refuse("answer", answer, "a table with the lines the teacher typed")
            lines = answer.get("lines", [])
            if not isinstance(lines, list) or not all(isinstance(x, str) and not text_problem(x) for x in lines):
                raise _refuse("answer.lines", lines, f"a list of the lines the teacher typed, each {TEXT_ACCEPTED}")
        except TranscriptError as error:
            raise TranscriptError(f"{path}: line {line}: {error}") from None
    return [record for _, record in numbered]


# -- checking a recorded turn before it is replayed -------------------------------------------------------------
def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _refuse(field_name: str, value, expected: str) -> TranscriptError:
    shown = json.dumps(value)
    if len(shown) > 80:  # a long value is shortened, and says so
        shown = f"{shown[:80]}... ({len(shown)} characters)"
    return TranscriptError(f"'{field_name}' is {shown} (expected {expected})")


def check_turn_record(record: dict, expected_turn: int, turns: int, concepts, feature_names) -> None:
    """Refuse a malformed turn record: ``'field' is VALUE (expected ...)``; the caller names the file and line."""
    turn = record.get("turn")
    if not _is_int(turn) or turn != expected_turn:
        raise _refuse("turn", turn, f"turn {expected_turn}: turns are whole numbers, in order from 1")
    if turn > turns:
        raise _refuse("turn", turn, f"at most {turns}, the session's number of turns")
    if not _is_int(record.get("scene_id")):
        raise _refuse("scene_id", record.get("scene_id"), "a whole number")
    for name in ("time", "ended", "cost", "budget_left"):
        if name in record and not _is_number(record[name]):
            raise _refuse(name, record[name], "a finite number")
    action = _check_action(record.get("action"), concepts)
    _check_answer(record.get("answer"), action, concepts, feature_names)
    undid = record.get("undid", [])
    if not isinstance(undid, list) or not all(_is_int(t) and 1 <= t < turn for t in undid):
        raise _refuse("undid", undid, f"a list of earlier turn numbers, 1 to {turn - 1}")
    for name in ("gesture", "fetched"):
        if name in record and not isinstance(record[name], dict):
            raise _refuse(name, record[name], "a table")
    if "fetched" in record and not isinstance(record["fetched"].get("kind"), str):
        raise _refuse("fetched.kind", record["fetched"].get("kind"), "the name of the fetched object kind")
    if "question" in record and not isinstance(record["question"], str):
        raise _refuse("question", record["question"], "the question's text")
    _check_model(record.get("model"), concepts)


def _check_action(action, concepts) -> str:
    kinds = "label with an object number from 1, demo with a concept, feature or none"
    kind = action.get("kind") if isinstance(action, dict) else None
    if kind not in ("label", "demo", "feature", "none"):
        raise _refuse("action", action, kinds)
    if kind == "label" and not (_is_int(action.get("object")) and action["object"] >= 1):
        raise _refuse("action.object", action.get("object"), "an object number from 1")
    if kind == "demo" and action.get("concept") not in concepts:
        raise _refuse("action.concept", action.get("concept"), f"one of {', '.join(concepts)}")
    return kind


def _check_answer(answer, action: str, concepts, feature_names) -> None:
    if answer is None:
        return
    if not isinstance(answer, dict):
        raise _refuse("answer", answer, "a table with kind, raw, parsed, lines and seconds")
    kind = answer.get("kind", "answer" if answer.get("parsed") is not None else "skip")
    allowed = ("none",) if action == "none" else tuple(k for k in ANSWER_KINDS if k != "none")
    if action == "label":
        allowed = tuple(k for k in allowed if k != "absent")
    if kind not in allowed:
        raise _refuse("answer.kind", kind, f"one of {', '.join(allowed)} for a {action} query")
    parsed = answer.get("parsed")
    if kind == "answer" and action == "label" and parsed not in concepts:
        raise _refuse("answer.parsed", parsed, f"one of {', '.join(concepts)}")
    if kind == "answer" and action == "demo" and not (_is_int(parsed) and parsed >= 1):
        raise _refuse("answer.parsed", parsed, "the number of the object shown, from 1")
    if kind == "answer" and action == "feature":
        if not isinstance(parsed, list) or not parsed or not all(isinstance(n, str) for n in parsed):
            raise _refuse("answer.parsed", parsed, "a non-empty list of feature names")
        unknown = [name for name in parsed if name not in feature_names]
        if unknown:
            raise _refuse("answer.parsed", unknown, "names from this session's feature catalogue")
    lines = answer.get("lines", [])
    if not isinstance(lines, list) or not all(isinstance(line, str) and not text_problem(line) for line in lines):
        raise _refuse("answer.lines", lines, f"a list of the lines the teacher typed, each {TEXT_ACCEPTED}")
    seconds = answer.get("seconds", 0.0)
    if not (_is_number(seconds) and seconds >= 0):
        raise _refuse("answer.seconds", seconds, "zero or more seconds")
    if "channels" in answer:  # a page's session: how each line came, and the page's answer time
        channels, times = answer["channels"], answer.get("page_seconds", [])
        if not (isinstance(channels, list) and len(channels) == len(lines) and all(c in CHANNELS for c in channels)):
            raise _refuse("answer.channels", channels, f"one of {', '.join(CHANNELS)} for each line")
        if not (isinstance(times, list) and len(times) == len(lines)
                and all(t is None or (_is_number(t) and t >= 0) for t in times)):
            raise _refuse("answer.page_seconds", times, "null or zero or more seconds for each line")


def _check_model(model, concepts) -> None:
    if model is None:
        return
    examples = model.get("examples") if isinstance(model, dict) else None
    if not isinstance(examples, dict) or set(examples) != set(concepts) or \
            not all(_is_int(n) and n >= 0 for n in examples.values()):
        raise _refuse("model.examples", examples, f"a count of zero or more for each of {', '.join(concepts)}")
    in_use = model.get("features_in_use")
    if in_use is not None and not (_is_int(in_use) and in_use >= 1):
        raise _refuse("model.features_in_use", in_use, "a whole number of at least 1")


# -- comparing a replayed turn with its record -----------------------------------------------------------------
GESTURE_TOLERANCE = 0.005  # metres (or simulated seconds) a repeated gesture may differ by


def scene_check(scene) -> dict:
    """A small fingerprint of a scene's feature rows, recorded so that a resume can tell it is the same scene."""
    return {"objects": int(scene.n_objects), "feature_sum": round(float(np.nansum(scene.X)), 6)}


def scene_difference(recorded, scene) -> str:
    """How a recorded scene fingerprint differs from ``scene`` ('' when it matches or none was recorded)."""
    if not isinstance(recorded, dict):
        return ""
    now = scene_check(scene)
    if recorded.get("objects") != now["objects"]:
        return f"{recorded.get('objects')} objects recorded, {now['objects']} rebuilt"
    total = recorded.get("feature_sum")
    if not isinstance(total, (int, float)) or not math.isclose(total, now["feature_sum"], rel_tol=1e-6,
                                                                abs_tol=1e-6):
        return f"feature sum {total} recorded, {now['feature_sum']} rebuilt"
    return ""


def gesture_difference(recorded, gesture: dict) -> str:
    """How a repeated gesture differs from the recorded one ('' when it matches within a few millimetres)."""
    if not isinstance(recorded, dict):
        return ""
    for key, value in recorded.items():
        again = gesture.get(key)
        if isinstance(value, bool) or isinstance(again, bool):
            if key in gesture and value != again:
                return f"{key} {value} recorded, {again} repeated"
        elif isinstance(value, (int, float)) and isinstance(again, (int, float)):
            if abs(value - again) > GESTURE_TOLERANCE:
                return f"{key} {value} recorded, {again} repeated"
    return ""


def scene_range_problem(action: Action, outcome: Outcome, scene) -> str:
    """An object number of the record that this scene does not have ('' when all are in range)."""
    n = scene.n_objects
    if action.kind == "label" and not 0 <= action.object_index < n:
        return f"'action.object' is {action.object_index + 1} (expected an object number from 1 to {n} of this scene)"
    if action.kind == "demo" and outcome.kind == "answer" and not 0 <= outcome.value < n:
        return f"'answer.parsed' is {outcome.value + 1} (expected an object number from 1 to {n} of this scene)"
    return ""


def model_difference(record: dict, summary: dict, budget_left: float) -> str:
    """How the replayed model and budget differ from the recorded ones ('' when they agree)."""
    model = record.get("model") or {}
    if model.get("examples") is not None and model["examples"] != summary["examples"]:
        return f"replaying the transcript gives {summary['examples']} examples, the transcript says {model['examples']}"
    if model.get("features_in_use") is not None and model["features_in_use"] != summary["features_in_use"]:
        return (f"replaying the transcript gives {summary['features_in_use']} features in use, the transcript says "
                f"{model['features_in_use']}")
    if "budget_left" in record and not math.isclose(record["budget_left"], budget_left, abs_tol=1e-9):
        return (f"replaying the transcript leaves {budget_left:g} of the budget, the transcript says "
                f"{record['budget_left']}")
    return ""


def question_difference(recorded: str, action: Action, describer, concepts) -> str:
    """How a recorded question differs from the one the rebuilt scene gives ('' when they agree)."""
    description = describer.describe(action.object_index) if action.kind == "label" else ""
    asked = question_text(action, description=description, concepts=concepts, n_objects=describer.scene.n_objects)
    if recorded == asked:
        return ""
    if action.kind == "label":  # a transcript from before the teacher's viewpoint, or before distinct descriptions
        old = SceneDescriber(describer.scene, describer.locations, OLD_WORLD_VIEWPOINT)
        for earlier in (old.describe(action.object_index), old.describe(action.object_index, distinct=False),
                        describer.describe(action.object_index, distinct=False)):
            if recorded == question_text(action, description=earlier, concepts=concepts,
                                         n_objects=describer.scene.n_objects):
                return ""
    return (f"the recorded question {recorded!r} is not the replay's {asked!r}: the transcript was made with another "
            "seed, task or kitchen")
