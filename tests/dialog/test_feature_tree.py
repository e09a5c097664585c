"""The feature-subset question: a numbered tree, chosen (HFS) or ignored (HFR) by number or name."""

import pytest

from dialog.language.feature_tree import FeatureTree

NAMES = ("colour.red", "colour.green", "colour.blue", "size.length", "size.height", "weight", "arm.joint1",
         "hand.x")
GROUPS = [("object/appearance/colour", "How red"), ("object/appearance/colour", "How green"),
          ("object/appearance/colour", "How blue"), ("object/geometry/size", "Length"),
          ("object/geometry/size", "Height"), ("object/weight", "Weight"), ("robot/arm", "Joint 1"),
          ("robot/hand", "Hand x")]


@pytest.fixture
def tree():
    return FeatureTree(NAMES, GROUPS)


def test_the_tree_is_numbered_in_column_order(tree):
    lines = tree.lines()
    assert lines[:4] == ["1 object", "  1.1 appearance", "    1.1.1 colour", "      1.1.1.1 colour.red: How red"]
    assert "  2.2 hand" in lines and "    2.2.1 hand.x: Hand x" in lines
    assert tree.group_of(3) == "object/geometry/size"


@pytest.mark.parametrize("text, chosen", [
    ("1.1", (0, 1, 2)), ("1.1, 1.2.1.2", (0, 1, 2, 4)), ("1.1-1.2", (0, 1, 2, 3, 4)),
    ("colour and size", (0, 1, 2, 3, 4)),
    ("use: weight", (5,)), ("all", tuple(range(8))), ("ignore 2", (0, 1, 2, 3, 4, 5)),
    ("all but 2, 1.3", (0, 1, 2, 3, 4)), ("Without robot", (0, 1, 2, 3, 4, 5)), ("COLOUR.RED 1.2", (0, 3, 4)),
])
def test_answers_choose_or_ignore(tree, text, chosen):
    reading = tree.read(text)
    assert (reading.kind, reading.value) == ("answer", chosen)


@pytest.mark.parametrize("text, fragment", [("1.9", "'1.9'"), ("smell, 1.1", "'smell'"), ("ignore all", "no feature"),
                                            ("", "empty"), ("1.2-1.1", "'1.2-1.1'")])
def test_unknown_items_are_named_never_guessed(tree, text, fragment):
    reading = tree.read(text)
    assert reading.kind == "unreadable" and fragment in reading.message and "'ignore'" in reading.message


def test_commands_pass_through(tree):
    assert tree.read("why").kind == "why" and tree.read("skip").kind == "skip"


def test_numbers_for_picks_whole_groups_where_possible(tree):
    assert tree.numbers_for(range(6)) == ["1"]
    assert tree.numbers_for([0, 1, 2, 4]) == ["1.1", "1.2.1.2"]
    for indices in ([0], [3, 4, 7], [5, 6], list(range(8))):
        assert tree.read(", ".join(tree.numbers_for(indices))).value == tuple(indices)


def test_the_real_catalogue_builds_a_tree():
    from bullet_world.features import feature_catalogue

    names = [info.name for info in feature_catalogue()]
    tree = FeatureTree(names)
    leaves = [node for node in tree.nodes() if node.feature is not None]
    assert sorted(node.feature for node in leaves) == list(range(len(names)))
    text = "\n".join(tree.lines())
    assert all(f"{node.number} {node.name}: {node.description}" in text for node in leaves)


@pytest.mark.parametrize("text, fragment", [("1.1-1.9", "'1.1-1.9'"), ("%all%", "'%all%'"), ("1.1 <the>", "'<the>'"),
                                            ("-1", "numbered 1 to 2"), ("1.1\x00", "control character"),
                                            ("\u202e1.1", "text-direction"), ("1.1 " * 100, "too long")])
def test_feature_answers_are_never_guessed(tree, text, fragment):
    reading = tree.read(text)
    assert reading.kind == "unreadable" and fragment in reading.message and "'ignore'" in reading.message


def test_a_symbol_line_is_no_command(tree):
    assert tree.read("%s").kind == "unreadable" and tree.read("s").kind == "skip"


# -- a tree longer than a screen: groups first, "more N" opens one ------------------------------------------
def real_tree():
    from bullet_world.features import feature_catalogue

    return FeatureTree([info.name for info in feature_catalogue()])


def test_a_small_tree_is_shown_whole_and_a_group_name_chooses(tree):
    assert not tree.collapsed and tree.overview() == tree.lines()
    assert (tree.read("appearance").kind, tree.read("appearance").value) == ("answer", (0, 1, 2))
    opened = tree.read("more 1.2")
    assert opened.kind == "more" and opened.value == ("1.2",)
    assert opened.message.splitlines() == ["1.2 geometry, 2 features (say '1.2' to use all of them):", "  1.2.1 size",
                                           "    1.2.1.1 size.length: Length", "    1.2.1.2 size.height: Height"]


def test_the_real_tree_shows_its_groups_in_twenty_lines_with_counts():
    big = real_tree()
    assert big.collapsed and len(big.lines()) > 100
    lines = big.overview()
    assert len(lines) <= 20 and all(len(line) <= 120 for line in lines)
    groups = [node for node in big.nodes() if node.feature is None and node.number.count(".") <= 1]
    for node in groups:
        count = len(node.leaves())
        assert any(line.strip().startswith(f"{node.number} {node.name}: {count} feature") for line in lines)
    assert "more" in lines[-1]


@pytest.mark.parametrize("text, number", [("more 3", "3"), ("More 1.1", "1.1"), ("open group 2", "2"),
                                          ("appearance", "1.1"), ("more light", "2.2"), ("expand the 3.3", "3.3")])
def test_more_or_a_bare_group_name_opens_a_group_of_the_real_tree(text, number):
    big = real_tree()
    reading = big.read(text)
    assert reading.kind == "more" and reading.value == (number,)
    node = big.by_number[number]
    assert reading.message.splitlines()[0].startswith(f"{number} {node.name}, {len(node.leaves())} feature")
    assert len(reading.message.splitlines()) <= 40


def test_a_group_too_long_for_a_screen_opens_as_its_subgroups():
    big = real_tree()
    lines = big.read("more 1").message.splitlines()
    assert len(lines) <= 10 and any(line.startswith("  1.4 location: 25 features") for line in lines)
    assert lines[-1] == "(say 'more 1.1' to list one of them)"


def test_opening_costs_no_answer_and_choosing_still_works_on_the_real_tree():
    big = real_tree()
    appearance = tuple(big.by_number["1.1"].leaves())
    assert big.read("use appearance").value == appearance and big.read("1.1").value == appearance
    assert big.read("weight").kind == "answer"  # a feature's name chooses it
    assert set(big.read("ignore light").value) == set(range(len(big.feature_names))) - set(big.read("2.2").value)
    for text, fragment in (("more 9", "'9'"), ("more", "I can't open:"), ("more colour, size", "'colour, size'")):
        reading = big.read(text)
        assert reading.kind == "unreadable" and fragment in reading.message and "'ignore'" in reading.message


def test_the_question_stays_open_after_more_and_the_list_is_not_reprinted_after_undo():
    import io

    import numpy as np

    from dialog.clock import VirtualClock
    from dialog.language.parsing import AnswerParser
    from dialog.language.questions import Prompt
    from dialog.teachers.conversation import converse
    from dialog.teachers.terminal import TerminalTeacher
    from learning.actions import FeatureQuery
    from tests.dialog.fakes import CONCEPTS, FakeEnvironment

    big = real_tree()
    scene = FakeEnvironment().next_scene(np.random.default_rng(0))
    question = Prompt(1, 10, 5.0, FeatureQuery(), "Which features tell fruit and snack apart?", "", scene, CONCEPTS,
                      details=big.overview(), feature_tree=big)
    out = io.StringIO()
    teacher = TerminalTeacher(io.StringIO("more 1.1\nundo\n1.1, 1.2\n"), out, clock=VirtualClock())
    first = converse(teacher, question, AnswerParser(CONCEPTS), VirtualClock())
    assert (first.kind, first.lines) == ("undo", ["more 1.1", "undo"])
    second = converse(teacher, question, AnswerParser(CONCEPTS), VirtualClock())
    assert second.kind == "answer" and len(second.value) == 24
    text = out.getvalue()
    assert text.count("1 object: 51 features") == 1 and text.count("1.1.1.1 colour.red") == 1
    assert len(text.splitlines()) < 50
