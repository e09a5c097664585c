"""Messages from the page become the line a person would type, or are refused naming what is accepted."""

import json

import pytest

from dialog.web.messages import MAX_MESSAGE_BYTES, Asked, decode, read_message, read_screen
from learning.errors import MessageError, TeachbotError

CONCEPTS = ("main dish", "snack", "fruit", "beverage")
LABEL = Asked(4, "label", CONCEPTS, 12)
DEMO = Asked(5, "demo", CONCEPTS, 12)
FEATURE = Asked(6, "feature", CONCEPTS, 12, frozenset({"1", "1.1", "1.2", "2", "2.1"}))


@pytest.mark.parametrize("message, asked, line, channel", [
    ({"type": "concept", "concept": "fruit"}, LABEL, "fruit", "button"),
    ({"type": "command", "command": "don't know"}, LABEL, "don't know", "button"),
    ({"type": "command", "command": "undo"}, FEATURE, "undo", "button"),
    ({"type": "command", "command": "none"}, DEMO, "none", "button"),
    ({"type": "pick", "object": 12}, DEMO, "number 12", "click"),
    ({"type": "object", "object": 3}, DEMO, "number 3", "button"),
    ({"type": "typed", "text": "a frut, I think"}, LABEL, "a frut, I think", "typed"),
    ({"type": "features", "numbers": ["1.1", "2"], "mode": "use"}, FEATURE, "1.1, 2", "button"),
    ({"type": "features", "numbers": ["1"], "mode": "ignore"}, FEATURE, "ignore 1", "button"),
])
def test_each_way_of_answering_becomes_a_typed_line(message, asked, line, channel):
    answer = read_message({**message, "question": asked.question, "page_ms": 1234}, asked)
    assert (answer.line, answer.channel, answer.page_seconds) == (line, channel, 1.234)


def test_a_click_on_the_picture_resolves_to_the_object_under_it():
    answer = read_message({"type": "click", "question": 5, "x": 0.5, "y": 0.25}, DEMO,
                          lambda x, y: 6 if (x, y) == (0.5, 0.25) else None)
    assert answer.line == "number 7"
    with pytest.raises(MessageError, match="a click on no object"):
        read_message({"type": "click", "question": 5, "x": 0.1, "y": 0.1}, DEMO, lambda x, y: None)


@pytest.mark.parametrize("message, asked, says", [
    ({"type": "concept", "concept": "DROP TABLE", "question": 4}, LABEL, "accepted: main dish, snack"),
    ({"type": "concept", "concept": "fruit", "question": 3}, LABEL, "the open question 4"),
    ({"type": "concept", "concept": "fruit", "question": True}, Asked(1, "label", CONCEPTS, 12), "open question"),
    ({"type": "concept", "concept": "fruit", "question": 5}, DEMO, "for a demo question"),
    ({"type": "pick", "object": 13, "question": 5}, DEMO, "accepted: 1 to 12"),
    ({"type": "pick", "object": 2.0, "question": 5}, DEMO, "accepted: 1 to 12"),
    ({"type": "pick", "object": 2, "question": 4}, LABEL, "accepted only when asked to show"),
    ({"type": "click", "x": 2, "y": 0.5, "question": 5}, DEMO, "x and y from 0 to 1"),
    ({"type": "command", "command": "none", "question": 4}, LABEL, "accepted: why, undo"),
    ({"type": "command", "command": "rm -rf", "question": 5}, DEMO, "command \"rm -rf\""),
    ({"type": "features", "numbers": ["9.9"], "mode": "use", "question": 6}, FEATURE, "feature tree shown"),
    ({"type": "features", "numbers": ["1", "1"], "mode": "use", "question": 6}, FEATURE, "distinct"),
    ({"type": "features", "numbers": ["1"], "mode": "all", "question": 6}, FEATURE, "accepted: use, ignore"),
    ({"type": "typed", "text": "a\nb", "question": 4}, LABEL, "one line"),
    ({"type": "typed", "text": "x" * 1001, "question": 4}, LABEL, "at most 1000"),
    ({"type": "typed", "text": "fruit", "question": 4, "as": "admin"}, LABEL, "unknown fields \"as\""),
    ({"type": "typed", "text": "fruit", "question": 4, "page_ms": -1}, LABEL, "page_ms -1"),
    ({"type": "eval", "question": 4}, LABEL, "accepted: typed, concept"),
    ({"type": "typed", "text": "fruit", "question": 4}, None, "no question is open"),
])
def test_forged_stale_and_malformed_messages_are_refused_in_one_line(message, asked, says):
    with pytest.raises(MessageError) as refused:
        read_message(message, asked)
    assert says in str(refused.value) and "\n" not in str(refused.value)
    assert isinstance(refused.value, TeachbotError)


@pytest.mark.parametrize("raw, says", [
    ("x" * (MAX_MESSAGE_BYTES + 1), "at most 4096 bytes"),
    ("{nope", "not JSON"),
    (b"\xff\xfe", "not JSON"),
    ("[1, 2]", "a JSON list"),
    ("42", "a JSON int"),
])
def test_what_is_not_one_small_json_object_is_refused(raw, says):
    with pytest.raises(MessageError, match=says):
        decode(raw)
    assert decode(json.dumps({"type": "typed"})) == {"type": "typed"}


DEEP = "[" * 1500 + "]" * 1500


@pytest.mark.parametrize("message, asked, says", [
    ({"type": "typed", "text": "\ud800zz", "question": 4}, LABEL, "U+D800, half of a surrogate pair"),
    ({"type": "typed", "text": "fr\x00uit", "question": 4}, LABEL, "U+0000, a control character"),
    ({"type": "typed", "text": "fruit\x1b[2J", "question": 4}, LABEL, "U+001B, a control character"),
    ({"type": "typed", "text": "fruit\x85", "question": 4}, LABEL, "U+0085, a control character"),
    ({"type": "typed", "text": "a\tb", "question": 4}, LABEL, "U+0009, a control character"),
    ({"type": ["concept"], "concept": "fruit", "question": 4}, LABEL, "message type [\"concept\"]"),
    ({"type": {}, "concept": "fruit", "question": 4}, LABEL, "message type {}"),
    ({"type": "concept", "concept": "fruit", "question": 4, "page_ms": int("9" * 401)}, LABEL, "page_ms 999"),
    ({"type": "click", "x": int("9" * 401), "y": 0.5, "question": 5}, DEMO, "x and y from 0 to 1"),
    ({"type": "click", "x": 0.5, "y": -int("9" * 401), "question": 5}, DEMO, "x and y from 0 to 1"),
    ({"type": "concept", "concept": "fruit", "question": 4.0}, LABEL, "question 4.0"),
    ({"type": "concept", "concept": "fruit", "question": "4"}, LABEL, "question \"4\""),
    ({"type": "typed", "text": json.loads("[" * 900 + "]" * 900), "question": 4}, LABEL, "typed text [[[["),
])
def test_text_that_cannot_be_kept_and_odd_json_values_are_refused_in_one_line(message, asked, says):
    """Issue 42, cases 1 and 2: each of these raised TypeError, OverflowError or RecursionError, or was taken."""
    with pytest.raises(MessageError) as refused:
        read_message(message, asked, lambda x, y: 0)
    assert says in str(refused.value) and "\n" not in str(refused.value)
    str(refused.value).encode("utf-8")  # the refusal itself can be sent and logged


def test_a_page_ms_of_any_length_and_a_whole_click_are_numbers():
    assert read_message({"type": "concept", "concept": "fruit", "question": 4, "page_ms": 0}, LABEL).page_seconds == 0
    assert read_message({"type": "click", "x": 1, "y": 0, "question": 5}, DEMO, lambda x, y: 2).line == "number 3"


@pytest.mark.parametrize("raw", [DEEP, '{"type": "typed", "question": 4, "text": ' + DEEP + "}"])
def test_deeply_nested_json_is_refused_not_a_recursion_error(raw):
    assert len(raw.encode()) <= MAX_MESSAGE_BYTES
    with pytest.raises(MessageError, match="nests JSON too deeply"):
        decode(raw)


SCREEN = {"id": 7, "items": [{"kind": "likert", "low": 1, "high": 5}, {"kind": "text"}]}


@pytest.mark.parametrize("answers, screen_id, says", [
    (["3", "fine\ud800"], 7, "item 2: a text (character 5 is U+D800, half of a surrogate pair"),
    (["3", "fine\x07"], 7, "item 2: a text (character 5 is U+0007, a control character)"),
    (["\u00b2", ""], 7, "item 1"),  # a digit int() refuses
    (["\u0663", ""], 7, "item 1"),  # an Arabic-Indic 3 is not a point of the scale's radio buttons
    (["3", ""], 7.0, "screen 7.0"),
])
def test_a_study_screen_refuses_unkeepable_text_odd_digits_and_float_ids(answers, screen_id, says):
    with pytest.raises(MessageError) as refused:
        read_screen({"type": "screen", "screen": screen_id, "answers": answers}, SCREEN)
    assert says in str(refused.value)


def test_a_study_screen_keeps_line_breaks_and_tabs_in_free_text():
    assert read_screen({"type": "screen", "screen": 7, "answers": ["5", "two\nlines\tand a tab"]}, SCREEN) == \
        [5, "two\nlines\tand a tab"]
