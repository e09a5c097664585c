"""The kinds of file ``fuzz_files.py`` mutates: how to make a good one, how to break it, and which command reads it.

A mutation is ``(description, breaks_rule, apply)``: ``apply(path, rng)`` changes the file in place;
``breaks_rule`` says the result breaks a rule the docs state (a wrong type, an unknown field, a value out of
range, a duplicated record, a header that disagrees with the study file, a weights file that does not match its
recorded SHA-256), so accepting it silently is a failure. Byte-level mutations (a cut, a flipped byte, a deleted
or swapped line) may or may not leave a valid file; for them only tracebacks, hangs and lost bytes count.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]

# -- byte-level mutations (any file) -------------------------------------------------------------------------------
JUNK = (b"\xff\xfe", b"\x00", b"\r", "\u202e\U0001f600".encode(), b"\\u0000", b"\x1b[2J", b"'; DROP TABLE x; --",
        b"%s%n")


def _cut(path, rng):
    data = path.read_bytes()
    path.write_bytes(data[:int(rng.integers(0, max(1, len(data))))])


def _flip(path, rng):
    data = bytearray(path.read_bytes())
    if data:
        data[int(rng.integers(len(data)))] ^= 1 << int(rng.integers(8))
    path.write_bytes(bytes(data))


def _insert(path, rng):
    data = path.read_bytes()
    at = int(rng.integers(0, len(data) + 1))
    path.write_bytes(data[:at] + JUNK[int(rng.integers(len(JUNK)))] + data[at:])


def _lines(path) -> list[bytes]:
    return path.read_bytes().splitlines(keepends=True)


def _delete_line(path, rng):
    lines = _lines(path)
    if lines:
        del lines[int(rng.integers(len(lines)))]
    path.write_bytes(b"".join(lines))


def _swap_lines(path, rng):
    lines = _lines(path)
    if len(lines) > 1:
        i, j = rng.choice(len(lines), 2, replace=False)
        lines[i], lines[j] = lines[j], lines[i]
    path.write_bytes(b"".join(lines))


def _deep(path, rng):
    lines = _lines(path)
    at = int(rng.integers(0, len(lines) + 1))
    opener = b"x = " + b"[" * 5000 + b"\n" if path.suffix == ".toml" else b"[" * 100000 + b"\n"
    path.write_bytes(b"".join(lines[:at] + [opener] + lines[at:]))


def _binary(path, rng):
    path.write_bytes(rng.bytes(int(rng.integers(1, 4096))))


def _empty(path, rng):
    path.write_bytes(b"")


def _huge(path, rng):
    path.write_bytes(path.read_bytes() + b"#" * (1 << 20) + b"\n")


BYTE_MUTATIONS = [("cut at a random byte", _cut), ("one bit flipped", _flip), ("junk bytes inserted", _insert),
                  ("a line deleted", _delete_line), ("two lines swapped", _swap_lines),
                  ("nesting 5000/100000 deep", _deep), ("random binary", _binary), ("emptied", _empty),
                  ("1 MB comment appended", _huge)]

# -- structured mutations -----------------------------------------------------------------------------------------
WRONG_TYPES = {int: ("abc", True, [1], {"x": 1}), float: ("abc", True, [1.5], {"x": 1}), str: (42, True, [], {"x": 1}),
               bool: ("yes", 1, [True]), list: ("x", {"x": 1}, 7), dict: (1, "x", [1])}


def _leaves(table, prefix=()):
    """Every (key path, value) of a parsed TOML table, lists' items included."""
    items = table.items() if isinstance(table, dict) else enumerate(table)
    for key, value in items:
        path = (*prefix, key)
        if isinstance(value, (dict, list)) and value:
            yield path, value
            yield from _leaves(value, path)
        else:
            yield path, value


def _toml_value(value) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    return repr(value)


def dump_toml(table: dict) -> str:
    """TOML text for a parsed table: every value inline under its dotted key path (what tomllib reads back)."""
    lines = []
    for key, value in table.items():
        lines.append(f"{json.dumps(str(key))} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def _set(table, path, value):
    for key in path[:-1]:
        table = table[key]
    table[path[-1]] = value


def wrong_type(skip=()):
    """Set one leaf (not under a key in ``skip``) to a value of another type: every field has one type."""
    def apply(path, rng):
        table = tomllib.loads(path.read_text(encoding="utf-8"))
        leaves = [(p, v) for p, v in _leaves(table) if not any(k in skip for k in p if isinstance(k, str))
                  and type(v) in WRONG_TYPES]
        where, value = leaves[int(rng.integers(len(leaves)))]
        choices = WRONG_TYPES[type(value)]
        _set(table, where, choices[int(rng.integers(len(choices)))])
        path.write_text(dump_toml(table), encoding="utf-8")
    return apply


def unknown_field(path, rng):
    table = tomllib.loads(path.read_text(encoding="utf-8"))
    table["zz_unknown_field"] = 1
    path.write_text(dump_toml(table), encoding="utf-8")


def set_toml(key_path, value):
    def apply(path, rng):
        table = tomllib.loads(path.read_text(encoding="utf-8"))
        _set(table, key_path, value)
        path.write_text(dump_toml(table), encoding="utf-8")
    return apply


def set_record(line, key_path, values):
    """Set a field of the JSON record on ``line`` (0 the header; -1 the last) to one of ``values``."""
    def apply(path, rng):
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        index = line if line >= 0 else len(lines) + line
        record = json.loads(lines[index])
        _set(record, key_path, values[int(rng.integers(len(values)))])
        lines[index] = json.dumps(record, ensure_ascii=False) + "\n"
        path.write_text("".join(lines), encoding="utf-8")
    return apply


def duplicate_line(path, rng):
    lines = _lines(path)
    at = int(rng.integers(1, len(lines)))
    path.write_bytes(b"".join(lines[:at + 1] + [lines[at]] + lines[at + 1:]))


def replace_text(text, value):
    return lambda path, rng: path.write_text(value(path.read_text(encoding="utf-8")) if callable(value)
                                             else value, encoding="utf-8")


RECORD = [1, 2, 3]
TRANSCRIPT_RULES = [
    ("turn 'three'", set_record(2, ("turn",), ["three", 0, True, 99])),
    ("scene_id not a number", set_record(1, ("scene_id",), ["x", None, 1.5])),
    ("action not a table", set_record(1, ("action",), [RECORD, "label", None])),
    ("action kind unknown", set_record(1, ("action", "kind"), ["fly", 3])),
    ("answer seconds negative", set_record(1, ("answer", "seconds"), [-1, "x", None])),
    ("answer lines not a list", set_record(1, ("answer", "lines"), ["x", [1]])),
    ("cost not a number", set_record(1, ("cost",), ["abc", [1]])),
    ("model examples wrong", set_record(1, ("model", "examples"), [[], "x", {"fruit": -1}])),
    ("header seed wrong", set_record(0, ("session", "seed"), [-1, "x", 1.5])),
    ("header turns wrong", set_record(0, ("session", "turns"), [0, "x"])),
    ("header strategy unknown", set_record(0, ("session", "strategy"), ["clever", 3])),
    ("header task unknown", set_record(0, ("session", "task"), ["nope", "../../etc/passwd"])),
    ("a turn line duplicated", duplicate_line),
    ("a record [1,2,3]", lambda p, rng: p.write_text(p.read_text() + "[1,2,3]\n")),
]
def drop_field(line, key):
    """Remove a field of the JSON record on ``line`` (a turn written without its answer, say)."""
    def apply(path, rng):
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        record = json.loads(lines[line])
        record.pop(key, None)
        lines[line] = json.dumps(record, ensure_ascii=False) + "\n"
        path.write_text("".join(lines), encoding="utf-8")
    return apply


def torn_after_a_turn(path, rng):
    """Keep the header and the first turns, and a torn piece of the next line: a transcript that lost turns."""
    lines = _lines(path)
    keep = int(rng.integers(1, len(lines)))
    path.write_bytes(b"".join(lines[:keep]) + lines[keep][:int(rng.integers(0, len(lines[keep]) - 1))])


def lone_surrogate(line, key_path):
    """A JSON escape of half a surrogate pair (``"\\ud800zz"``) in a text field: valid JSON, not Unicode text."""
    def apply(path, rng):
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        index = line if line >= 0 else len(lines) + line
        record = json.loads(lines[index])
        _set(record, key_path, ["\ud800zz"] if key_path[-1] == "lines" else "\ud800zz")
        lines[index] = json.dumps(record, ensure_ascii=True) + "\n"  # the escape, as a page's JSON carries it
        path.write_text("".join(lines), encoding="utf-8")
    return apply


def device_link(path, rng):
    path.unlink()
    path.symlink_to("/dev/zero")  # never ends: a reader must refuse it before reading


def fifo(path, rng):
    path.unlink()
    os.mkfifo(path)  # blocks a reader that opens it: it must be refused unopened


STUDY_TRANSCRIPT_RULES = TRANSCRIPT_RULES + [
    ("header strategy of another condition", set_record(0, ("session", "strategy"), ["active", "passive"])),
    ("header seed edited", set_record(0, ("session", "seed"), [1, 12345])),
    ("header participant edited", set_record(0, ("session", "study", "participant"), ["P02", "P01\n"])),
    ("accuracy out of range", set_record(2, ("accuracy",), [7, -1, "x"])),
    # issue 42: the questionnaire beside it rated the whole session; every header field is the study run's
    ("torn after a turn, beside the questionnaire", torn_after_a_turn),
    ("a turn without its answer", drop_field(2, "answer")),
    ("header software edited", set_record(0, ("session", "study", "software"), ["hacked", 5, "", None])),
    ("header teacher edited", set_record(0, ("session", "teacher"), [{"kind": "terminal"}, {"kind": "replay"}])),
    ("header costs edited", set_record(0, ("session", "costs"), [{"label": 0, "demo": 0, "feature": 0, "none": 0}])),
    ("header unknown field", set_record(0, ("session", "zz_unknown"), [1])),
    ("an answer line a lone surrogate", lone_surrogate(1, ("answer", "lines"))),
]
QUESTIONNAIRE_RULES = [
    ("Likert 'seven'", set_record(1, ("value",), ["seven", 99, 0, True, 2.5])),
    ("item unknown", set_record(1, ("item",), ["nope", 7, None])),
    ("kind wrong", set_record(1, ("kind",), ["text", "x"])),
    ("text answer not text", set_record(-1, ("value",), [5, ["x"]])),
    ("header of another participant", set_record(0, ("questionnaire", "participant"), ["P02", "P01\n"])),
    ("header of another condition", set_record(0, ("questionnaire", "condition"), ["active", ""])),
    ("an answer duplicated", duplicate_line),
    ("an answer removed", lambda p, rng: p.write_text("".join(p.read_text().splitlines(keepends=True)[:-1]))),
    ("a line [1,2,3]", lambda p, rng: p.write_text(p.read_text() + "[1,2,3]\n")),
    ("text a lone surrogate", lone_surrogate(-1, ("value",))),
    ("header software edited", set_record(0, ("questionnaire", "software"), ["hacked", 5, None])),
]
REPLAY_RULES = [  # a transcript given to teach --teacher replay --replay
    ("a link to /dev/zero", device_link),
    ("a FIFO", fifo),
    ("answer not a table", set_record(1, ("answer",), [RECORD, "a fruit", None])),
    ("answer lines not a list", set_record(1, ("answer", "lines"), ["a fruit", [1], {"x": 1}])),
    ("turn not a number", set_record(1, ("turn",), ["three", 0, True, None])),
    ("a turn line duplicated", duplicate_line),
    ("an answer line a lone surrogate", lone_surrogate(1, ("answer", "lines"))),
    ("a record [1,2,3]", lambda p, rng: p.write_text(p.read_text() + "[1,2,3]\n")),
]
NOTE_RULES = [
    ("after_turns not a count", set_record(0, ("aborted", "after_turns"), ["abc", [1], -1, 999, None])),
    ("reason missing", set_record(0, ("aborted", "reason"), ["", 5, None])),
    ("note of another participant", set_record(0, ("aborted", "participant"), ["P01", "P03"])),
    ("note a list", replace_text(None, "[1, 2, 3]\n")),
    ("note twice", lambda p, rng: p.write_text(p.read_text() * 2)),
]
CONSENT_RULES = [  # issue 50: d/P01/consent.json, recorded once when P01 agreed (here: simulated)
    ("given not a way of giving it", set_record(0, ("consent", "given"), ["email", 3, None, "page"])),
    ("text_sha256 of another text", set_record(0, ("consent", "text_sha256"), ["0" * 64, "", 5])),
    ("consent of another participant", set_record(0, ("consent", "participant"), ["P02", "P01\n"])),
    ("time not a time", set_record(0, ("consent", "time"), ["yesterday", 5, None])),
    ("simulated flipped", set_record(0, ("consent", "simulated"), [False, "yes"])),
    ("consent unknown field", set_record(0, ("consent", "zz_unknown"), [1])),
    ("consent a list", replace_text(None, "[1, 2, 3]\n")),
    ("consent twice", lambda p, rng: p.write_text(p.read_text() * 2)),
    ("consent removed, the sessions kept", lambda p, rng: p.unlink()),
]
PRACTICE_RULES = TRANSCRIPT_RULES + [  # issue 50: d/P01/0-practice.jsonl, the practice round (no questionnaire)
    ("header strategy of a condition", set_record(0, ("session", "strategy"), ["dt-task", "passive"])),
    ("header seed edited", set_record(0, ("session", "seed"), [1, 12345])),
    ("header order of a condition", set_record(0, ("session", "study", "order"), [1, 3, -1])),
    ("header condition renamed", set_record(0, ("session", "study", "condition"), ["dt-task", "warm-up"])),
    ("header turns edited", set_record(0, ("session", "turns"), [8, 0])),
    ("a turn without its answer", drop_field(2, "answer")),
]
DEMO_RULES = [
    ("format wrong", lambda p, rng: _edit_json(p, "format", ["x", 3])),
    ("format_version wrong", lambda p, rng: _edit_json(p, "format_version", [99, "2"])),
    ("episodes not a list", lambda p, rng: _edit_json(p, "episodes", ["x", 5, {}])),
    ("feature_names wrong", lambda p, rng: _edit_json(p, "feature_names", [5, ["x"], []])),
]


def _edit_json(path, key, values):
    data = json.loads(path.read_text(encoding="utf-8"))
    data[key] = values[len(path.read_bytes()) % len(values)]
    path.write_text(json.dumps(data), encoding="utf-8")


POLICY_RULES = [
    ("weights outside the folder", set_toml(("policy", "weights"), "../../../etc/passwd")),
    ("weights an absolute path", set_toml(("policy", "weights"), "/etc/passwd")),
    ("weights the folder itself", set_toml(("policy", "weights"), ".")),
    ("layers wrong", set_toml(("policy", "layers"), [151, 64, 18])),
    ("a field of another type", wrong_type(skip=("provenance",))),
    ("an unknown field", unknown_field),
]


def npz_byte_change(mutate):
    """Any change to the weights' bytes breaks the SHA-256 the policy file records for them."""
    return mutate
