"""The page's words for a participant (dialog/web/words.py, issue 41 item 4): every feature group has plain words,
study texts name the page's buttons, a resumed page gets the conversation so far and an undo the budget back."""

from __future__ import annotations

import re

from bullet_world.features import feature_catalogue
from dialog.language.feature_tree import FeatureTree
from dialog.web import words
from dialog.web.teacher import WebTeacher, _tree_rows


def test_every_group_of_the_feature_catalogue_has_plain_words():
    groups = {"/".join(info.group.split("/")[:depth]) for info in feature_catalogue()
              for depth in range(1, info.group.count("/") + 2)}
    missing = sorted(groups - set(words.group_words()))
    assert not missing, f"add these groups to {words.GROUP_WORDS}: {missing}"


def test_the_feature_checkboxes_show_words_not_tree_numbers():
    tree = FeatureTree(["colour.red", "size.height", "location.x"])
    rows = {row["number"]: row for row in _tree_rows(tree)}
    assert rows["1.1.1"]["label"] == "its colour" and rows["1.1.1"]["group"]
    assert rows["1.1.1.1"]["label"].startswith("How red the object looks")
    assert {row["label"] for row in rows.values() if row["group"]} >= {"its size", "where it is"}


def test_study_texts_written_for_the_terminal_name_the_pages_buttons():
    assert words.for_page("Take a short break. Press Enter when you are ready.", "Go on") == \
        'Take a short break. Press "Go on" when you are ready.'
    assert words.for_page("Answer well; type 'why' to hear its reason.", "Begin") == \
        'Answer well; press "Why?" to hear its reason.'
    assert "numbers" not in words.feature_question(["fruit", "snack"]) and "Tick" in \
        words.feature_question(["fruit", "snack"])


def test_a_resumed_page_shows_each_earlier_question_and_its_answers():
    teacher = WebTeacher()
    teacher.recall([
        {"turn": 1, "action": {"kind": "label"}, "question": "What is number 3?",
         "answer": {"lines": ["why", "fruit"]}},
        {"turn": 2, "action": {"kind": "none"}, "answer": {}},
        {"turn": 3, "action": {"kind": "feature"}, "question": "Give the numbers...", "answer": {"raw": "1.1"}},
    ], ("fruit", "snack"))
    assert [(line["who"], line["text"]) for line in teacher.conversation] == [
        ("robot", "What is number 3?"), ("teacher", "why"), ("teacher", "fruit"),
        ("robot", words.feature_question(("fruit", "snack"))), ("teacher", "1.1")]


def test_an_undo_gives_the_budget_back_on_the_page_at_once():
    teacher, sent = WebTeacher(), []
    teacher.broadcast = sent.append
    teacher.current = {"id": 4, "budget_left": 32}
    teacher.budget_changed(35.0)
    assert teacher.snapshot()["question"]["budget_left"] == 35.0  # a reload sees it too
    assert sent == [{"type": "budget", "question": 4, "budget_left": 35.0}]
    teacher.show_budget = False  # a study hides the budget from its participants
    teacher.budget_changed(36.0)
    assert len(sent) == 1


def test_a_feature_answer_from_the_checkboxes_is_shown_in_their_words():
    rows = {row["number"]: row["label"] for row in _tree_rows(FeatureTree(["colour.red", "size.height"]))}
    assert words.answer_words("1.1, 1.2", rows) == "how it looks, its shape and size"
    assert words.answer_words("ignore 1.1", rows) == "these don't matter: how it looks"
    assert words.answer_words("fruit", rows) == "fruit" and words.answer_words("9.9", rows) == "9.9"


def test_feature_descriptions_lose_their_units_and_scales():
    from bullet_world.features import feature_catalogue

    shown = {info.name: words.plain_feature(info.name, info.description) for info in feature_catalogue()}
    for name, text in shown.items():
        assert not re.search(r"metres|radians|kilograms|decibels|quaternion|\(\s*[-+0-9]|\d\.\d", text), (name, text)
        assert text.strip() and text[0].isupper(), (name, text)
    assert shown["colour.red"] == "How red the object looks on average"
    assert len(set(shown.values())) == len(shown)  # no two checkboxes read the same


def test_the_participant_is_you_in_the_pages_session_lines():
    teacher = WebTeacher()
    teacher.say("Turn 3 · the teacher ended the session (quit).", echo=False)
    assert teacher.conversation[-1]["text"] == "Turn 3 · you stopped the session."


def test_a_resumed_page_says_an_earlier_feature_answer_in_words():
    teacher = WebTeacher()
    teacher.recall([{"turn": 1, "action": {"kind": "feature"}, "question": "Give the numbers...",
                     "answer": {"lines": ["why", "1.1, 1.2"]}}], ("fruit", "snack"), ["colour.red", "size.height"])
    assert [line["text"] for line in teacher.conversation if line["who"] == "teacher"] == [
        "why", "how it looks, its shape and size"]
