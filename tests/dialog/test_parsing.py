"""Tolerant answer reading: synonyms, plurals, case, typos with confirmation, numbers, commands."""

import pytest

from dialog.parsing import AnswerParser, edit_distance, typo_tolerance
from dialog.vocabulary import VocabularyError, clean, load_vocabulary, phrase, plural

CONCEPTS = ("main dish", "snack", "fruit", "beverage")


@pytest.fixture(scope="module")
def parser():
    return AnswerParser(CONCEPTS)


@pytest.mark.parametrize("text, concept", [
    ("fruit", "fruit"), ("a fruit", "fruit"), ("FRUITS!", "fruit"), ("  Fruit.  ", "fruit"),
    ("It's a snack, I think", "snack"), ("main dishes", "main dish"), ("Main-Dish", "main dish"),
    ("a drink", "beverage"), ("juice", "beverage"), ("an entree", "main dish"), ("3", "fruit"),
    ("frut", "fruit"), ("snak", "snack"), ("bevrage", "beverage"), ("maindish", "main dish"),
    ("fru\u0301it", "fruit"), ("\u00a0fruit\t", "fruit"), ("Beverages", "beverage"),
])
def test_concepts_are_read_in_many_forms(parser, text, concept):
    reading = parser.label(text)
    assert (reading.kind, reading.value) == ("answer", concept)


def test_a_corrected_typo_is_said_back(parser):
    assert "'frut' as 'fruit'" in parser.label("frut").message
    assert parser.label("fruit").message == ""


@pytest.mark.parametrize("text", ["fruit or snack", "a snack, no wait, a fruit"])
def test_two_concepts_named_ask_for_a_choice(parser, text):
    reading = parser.label(text)
    assert reading.kind in ("choose", "unreadable")
    if reading.kind == "choose":
        assert set(reading.choices) == {"fruit", "snack"}


def test_a_typo_close_to_two_concepts_asks_which(parser):
    close = AnswerParser(("pasta", "pastry"))
    reading = close.label("pastr")
    assert reading.kind == "choose" and set(reading.choices) == {"pasta", "pastry"}
    assert close.choice("2", reading.choices).value == "pastry"
    assert close.choice("pasta", reading.choices).value == "pasta"
    assert close.choice("no", reading.choices).kind == "reject"
    assert close.choice("maybe", reading.choices).kind == "unreadable"
    single = AnswerParser(("fruit",)).choice("yes", ("fruit",))
    assert single.value == "fruit"


@pytest.mark.parametrize("text", ["not a fruit", "great", "xyzzy", "apple pie", "7", "0", "no",
                                  "fruit" * 70, "\u6c34\u679c"])
def test_nothing_is_guessed(parser, text):
    reading = parser.label(text)
    assert reading.kind == "unreadable"
    assert reading.message and len(reading.message.splitlines()) == 1


def test_unreadable_messages_list_the_accepted_forms(parser):
    message = parser.label("xyzzy").message
    assert "main dish, snack, fruit, beverage" in message and "'skip'" in message and "'undo'" in message
    assert "1 to 12" in parser.demonstration("banana", 12, "fruit").message
    assert "'none'" in parser.demonstration("banana", 12, "fruit").message


@pytest.mark.parametrize("text, kind", [
    ("why", "why"), ("Why?", "why"), ("help", "help"), ("?", "help"), ("UNDO", "undo"), ("take that back", "undo"),
    ("skip", "skip"), ("pass", "skip"), ("quit", "quit"), ("exit", "quit"), ("I don't know", "dont_know"),
    ("dunno", "dont_know"), ("not sure", "dont_know"),
])
def test_commands_work_for_every_question(parser, text, kind):
    assert parser.label(text).kind == kind
    assert parser.demonstration(text, 8, "fruit").kind == kind


@pytest.mark.parametrize("text, index", [
    ("4", 3), ("number 4", 3), ("No. 4", 3), ("#4", 3), ("the 4th one", 3), ("four", 3), ("the fourth", 3),
    ("number twelve", 11), ("one", 0), ("it's number 7, the fruit", 6), ("fruit number 2", 1),
])
def test_demonstrations_by_number(parser, text, index):
    reading = parser.demonstration(text, 12, "fruit")
    assert (reading.kind, reading.value) == ("answer", index)


@pytest.mark.parametrize("text", ["none", "None here", "not here", "there is no fruit here", "nothing",
                                  "no fruit", "There isn't one", "nope"])
def test_absent_examples(parser, text):
    assert parser.demonstration(text, 12, "fruit").kind == "absent"


@pytest.mark.parametrize("text, fragment", [("13", "no object 13"), ("0", "no object 0"),
                                            ("4 and 7", "One number"), ("not 4", "not which"),
                                            ("that one", "didn't understand")])
def test_bad_demonstrations_say_what_was_wrong(parser, text, fragment):
    reading = parser.demonstration(text, 12, "fruit")
    assert reading.kind == "unreadable" and fragment in reading.message


def test_edit_distance_counts_typos():
    assert edit_distance("fruit", "fruit") == 0
    assert edit_distance("frut", "fruit") == 1
    assert edit_distance("fruti", "fruit") == 1  # swapped neighbours
    assert edit_distance("snack", "beverage", limit=2) == 3  # capped
    assert typo_tolerance("pop") == 0 and typo_tolerance("fruit") == 1 and typo_tolerance("beverage") == 2


def test_normalisation_and_plurals():
    assert clean("  FrUit\x00\x07 ") == "fruit"
    assert phrase("Main-Dish!!") == "main dish"
    assert [plural(w) for w in ("fruit", "dish", "berry", "day", "main dish")] == [
        "fruits", "dishes", "berries", "days", "main dishes"]


def test_a_broken_vocabulary_file_is_named(tmp_path):
    path = tmp_path / "vocabulary.toml"
    path.write_text("[synonyms]\nfruit = 'apple'\n")
    with pytest.raises(VocabularyError, match="vocabulary.toml"):
        load_vocabulary(path)
    with pytest.raises(VocabularyError, match="no such vocabulary file"):
        load_vocabulary(tmp_path / "missing.toml")
