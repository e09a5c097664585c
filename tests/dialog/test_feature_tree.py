"""The feature-subset question: a numbered tree, chosen (HFS) or ignored (HFR) by number or name."""

import pytest

from dialog.feature_tree import FeatureTree

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
