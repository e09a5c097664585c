"""Transcripts: a session header, one synced record per turn, and recovery from a line cut short."""

import json

import numpy as np
import pytest

from dialog.transcripts.jsonl import TranscriptWriter, drop_partial_tail, read_session, read_transcript


def test_header_then_turns(tmp_path):
    path = tmp_path / "t.jsonl"
    with TranscriptWriter(path) as writer:
        writer.write_header({"seed": 3, "task": "pack-lunchbox"})
        writer.write({"turn": 1, "answer": {"raw": "\u00e9t\u00e9"}})
        with pytest.raises(ValueError, match="first line"):
            writer.write_header({})
    header, records = read_session(path)
    assert header["seed"] == 3 and header["format"] == "teachbot-transcript" and header["version"] == 1
    assert records == [{"turn": 1, "answer": {"raw": "\u00e9t\u00e9"}}] == read_transcript(path)



def test_a_lone_surrogate_in_a_record_is_kept_and_the_turn_is_not_lost(tmp_path):
    """Issue 42, case 1: a string UTF-8 cannot hold raised UnicodeEncodeError here and the session lost its turn.
    Its record is written with the JSON escape instead; every other record stays byte-identical (UTF-8)."""
    path = tmp_path / "t.jsonl"
    with TranscriptWriter(path) as writer:
        writer.write({"turn": 1, "answer": {"raw": "\u00e9t\u00e9"}})
        writer.write({"turn": 2, "answer": {"lines": ["\ud800zz", "fruit"], "raw": "fruit"}})
        writer.write({"turn": 3, "answer": {"raw": "\u00e9"}})
    lines = path.read_bytes().splitlines()
    assert lines[0] == '{"turn": 1, "answer": {"raw": "\u00e9t\u00e9"}}'.encode("utf-8")
    assert b"\\ud800zz" in lines[1] and lines[1].isascii()
    assert [r["turn"] for r in read_transcript(path)] == [1, 2, 3]
    assert read_transcript(path)[1]["answer"]["lines"] == ["\ud800zz", "fruit"]

def test_a_line_cut_short_by_a_crash_is_dropped_on_append(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text('{"turn": 1}\n{"turn": 2}\n{"turn": 3, "answ')
    with pytest.raises(ValueError, match="line 3 is not a JSON record"):
        read_session(path)
    assert read_session(path, tolerate_partial_tail=True)[1] == [{"turn": 1}, {"turn": 2}]
    with TranscriptWriter(path, append=True) as writer:
        writer.write({"turn": 3})
    assert [r["turn"] for r in read_transcript(path)] == [1, 2, 3]
    assert drop_partial_tail(path) == 0


def test_a_partial_only_line_leaves_an_empty_file(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_bytes(b'{"sess')
    assert drop_partial_tail(path) == 6 and path.read_bytes() == b""


@pytest.mark.parametrize("content, fragment", [
    ('{"turn": 1}\n{"session": {"format": "teachbot-transcript"}}\n', "only line 1"),
    ('{"session": {"format": "other"}}\n', "not a teachbot-transcript header"),
    ('[1, 2]\n', "not a JSON object"),
    ('{"answer": 1}\n', "has no 'turn'"),
])
def test_bad_transcripts_are_named(tmp_path, content, fragment):
    path = tmp_path / "bad.jsonl"
    path.write_text(content)
    with pytest.raises(ValueError, match=fragment):
        read_session(path)


def test_each_record_is_on_disk_before_the_next_turn(tmp_path):
    path = tmp_path / "t.jsonl"
    writer = TranscriptWriter(path)
    writer.write({"turn": 1})
    assert json.loads(path.read_text()) == {"turn": 1}
    writer.close()


def test_a_session_recorded_with_other_concepts_or_features_is_refused():
    from dialog.session import SessionSettings, check_compatible
    from tests.dialog.fakes import FakeEnvironment

    env = FakeEnvironment()
    check_compatible({"concepts": list(env.concepts), "features": 3}, env, "t.jsonl")
    with pytest.raises(ValueError, match="recorded with 86 features; this kitchen gives 3"):
        check_compatible({"features": 86}, env, "t.jsonl")
    with pytest.raises(ValueError, match="recorded with the concepts"):
        check_compatible({"concepts": ["pasta"]}, env, "t.jsonl")
    with pytest.raises(ValueError, match="has no session header"):
        SessionSettings.from_header(None, "t.jsonl")
    with pytest.raises(ValueError, match="lacks budget"):
        SessionSettings.from_header({"task": "t", "kitchen": "k", "strategy": "s", "seed": 0, "turns": 3,
                                     "change_every": 1}, "t.jsonl")
    with pytest.raises(ValueError, match="teacher 'robot' is not one of"):
        SessionSettings(teacher={"kind": "robot"})


def test_turn_records_come_with_their_line_numbers(tmp_path):
    from dialog.transcripts.jsonl import read_numbered_session

    path = tmp_path / "t.jsonl"
    path.write_text('{"session": {"format": "teachbot-transcript"}}\n\n{"turn": 1}\n{"turn": 2}\n')
    header, numbered = read_numbered_session(path)
    assert header == {"format": "teachbot-transcript"} and numbered == [(3, {"turn": 1}), (4, {"turn": 2})]


def test_unreadable_lines_are_transcript_errors(tmp_path):
    from learning.errors import TranscriptError

    path = tmp_path / "t.jsonl"
    path.write_text('{"turn": 1}\nnot json\n')
    with pytest.raises(TranscriptError, match=r"t.jsonl: line 2 is not a JSON record"):
        read_session(path)


def test_a_bad_line_is_described_in_full_with_its_column(tmp_path):
    from learning.errors import TranscriptError

    path = tmp_path / "t.jsonl"
    path.write_text('{"turn": 1}\n{"turn": 2, "raw": "a\tb"}\n')
    with pytest.raises(TranscriptError) as raised:
        read_session(path)
    message = str(raised.value)
    assert message == (f"{path}: line 2 is not a JSON record: invalid control character '\\t' at column 22; every line "
                       "of a transcript is one JSON object, as teachbot writes it")
    path.write_text('{"turn": 1}\n{"turn": 2,\n{"turn": 3}\n')
    with pytest.raises(TranscriptError, match=r"line 2 is not a JSON record: expecting property name enclosed in "
                                              r"double quotes at the end of the line \(column 12\); every line"):
        read_session(path)


def test_a_long_bad_value_is_shortened_and_says_so():
    from dialog.transcripts.records import check_turn_record
    from learning.errors import TranscriptError

    with pytest.raises(TranscriptError) as raised:
        check_turn_record(good_record(scene_id=["x" * 200]), 2, 5, ("main dish", "snack", "fruit", "beverage"),
                          ("f1", "f2", "f3"))
    assert "... (" in str(raised.value) and "characters)" in str(raised.value)


def good_record(**changes):
    record = {"turn": 2, "time": 1.0, "scene_id": 1, "action": {"kind": "label", "object": 3},
              "answer": {"kind": "answer", "raw": "a fruit", "parsed": "fruit", "lines": ["a fruit"], "seconds": 0.5},
              "cost": 1.0, "budget_left": 3.0, "undid": [1],
              "model": {"examples": {"main dish": 0, "snack": 0, "fruit": 1, "beverage": 0}, "features_in_use": 3}}
    record.update(changes)
    return record


@pytest.mark.parametrize("changes, fragment", [
    ({"turn": 3}, "'turn' is 3 (expected turn 2"),
    ({"turn": 2.0}, "'turn' is 2.0 (expected turn 2"),
    ({"scene_id": None}, "'scene_id' is null"),
    ({"action": {"kind": "demo", "concept": "pasta"}}, "'action.concept' is \"pasta\""),
    ({"action": {"kind": "none"}}, "'answer.kind' is \"answer\" (expected one of none for a none query)"),
    ({"answer": {"kind": "absent"}}, "'answer.kind' is \"absent\""),
    ({"answer": {"kind": "answer", "parsed": "fruit", "lines": "a fruit"}}, "'answer.lines' is \"a fruit\""),
    ({"action": {"kind": "demo", "concept": "fruit"}, "answer": {"kind": "answer", "parsed": "2"}},
     "'answer.parsed' is \"2\" (expected the number of the object shown, from 1)"),
    ({"action": {"kind": "feature"}, "answer": {"kind": "answer", "parsed": []}}, "'answer.parsed' is []"),
    ({"undid": [2]}, "'undid' is [2]"),
    ({"budget_left": float("nan")}, "'budget_left' is NaN"),
    ({"model": {"examples": {"main dish": 0, "snack": 0, "fruit": -1, "beverage": 0}}}, "'model.examples'"),
    ({"model": {"examples": {"main dish": 0, "snack": 0, "fruit": 1, "beverage": 0}, "features_in_use": 0}},
     "'model.features_in_use' is 0"),
    ({"fetched": {"position": [0, 0, 0]}}, "'fetched.kind' is null"),
])
def test_a_malformed_turn_record_names_the_field_and_what_is_accepted(changes, fragment):
    from dialog.transcripts.records import check_turn_record
    from learning.errors import TranscriptError
    from tests.dialog.fakes import CONCEPTS

    check_turn_record(good_record(), 2, 5, CONCEPTS, ("f1", "f2", "f3"))
    with pytest.raises(TranscriptError) as caught:
        check_turn_record(good_record(**changes), 2, 5, CONCEPTS, ("f1", "f2", "f3"))
    assert str(caught.value).startswith(fragment)


def test_scene_and_gesture_fingerprints():
    from dialog.transcripts.records import gesture_difference, scene_check, scene_difference
    from tests.dialog.fakes import FakeEnvironment

    scene = FakeEnvironment().next_scene(np.random.default_rng(0))
    recorded = scene_check(scene)
    assert recorded["objects"] == 8 and scene_difference(recorded, scene) == "" == scene_difference(None, scene)
    other = FakeEnvironment().next_scene(np.random.default_rng(1))
    assert scene_difference(recorded, other).startswith("feature sum ")
    assert scene_difference({**recorded, "objects": 9}, scene) == "9 objects recorded, 8 rebuilt"
    gesture = {"reached": True, "horizontal_error_m": 0.004}
    assert gesture_difference(gesture, {"reached": True, "horizontal_error_m": 0.006}) == ""
    assert gesture_difference(gesture, {"reached": False, "horizontal_error_m": 0.004}) == "reached True recorded, " \
        "False repeated"
    assert "horizontal_error_m" in gesture_difference(gesture, {"reached": True, "horizontal_error_m": 0.02})
