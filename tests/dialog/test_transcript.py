"""Transcripts: a session header, one synced record per turn, and recovery from a line cut short."""

import json

import pytest

from dialog.transcript import TranscriptWriter, drop_partial_tail, read_session, read_transcript


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
