"""One question, one answer: help, why, ask-again, confirmation, deadlines."""

import numpy as np
import pytest

from dialog.clock import VirtualClock
from dialog.language.parsing import AnswerParser
from dialog.language.questions import Prompt
from dialog.teachers.conversation import converse
from learning.actions import DemoQuery, FeatureQuery, LabelQuery
from tests.dialog.fakes import CONCEPTS, FakeEnvironment


class ListTeacher:
    """Answers with the given lines (each after ``delay`` seconds on the clock), remembers what it heard."""

    def __init__(self, lines, clock=None, delay=0.0):
        self.lines, self.clock, self.delay = list(lines), clock, delay
        self.heard, self.shown = [], 0

    def show(self, prompt):
        self.shown += 1

    def listen(self, prompt, deadline):
        if self.clock is not None:
            self.clock.sleep(self.delay)
        return self.lines.pop(0) if self.lines else None

    def tell(self, text):
        self.heard.append(text)


@pytest.fixture
def scene():
    return FakeEnvironment().next_scene(np.random.default_rng(0))


def prompt(scene, action, deadline=None, tree=None):
    return Prompt(1, 10, 5.0, action, "What is this?", "I can't tell fruit from snack.", scene, CONCEPTS,
                  feature_tree=tree, deadline=deadline)


def test_help_why_and_unreadable_keep_the_question_open(scene):
    teacher = ListTeacher(["help", "why", "zzz", "", "a fruit"])
    outcome = converse(teacher, prompt(scene, LabelQuery(2)), AnswerParser(CONCEPTS), VirtualClock())
    assert (outcome.kind, outcome.value) == ("answer", "fruit")
    assert outcome.lines == ["help", "why", "zzz", "", "a fruit"]
    assert "synonyms" in teacher.heard[0].lower() and "'undo'" in teacher.heard[0]
    assert teacher.heard[1] == "Why I ask: I can't tell fruit from snack."
    assert "didn't understand 'zzz'" in teacher.heard[2] and "empty" in teacher.heard[3]


def test_close_candidates_are_confirmed_first(scene):
    parser = AnswerParser(("pasta", "pastry"))
    teacher = ListTeacher(["pastr", "maybe", "2"])
    outcome = converse(teacher, prompt(scene, LabelQuery(0)), parser, VirtualClock())
    assert (outcome.kind, outcome.value) == ("answer", "pastry")
    assert "Did you mean 1 pasta or 2 pastry?" in teacher.heard[0]
    rejected = ListTeacher(["pastr", "no", "pasta"])
    assert converse(rejected, prompt(scene, LabelQuery(0)), parser, VirtualClock()).value == "pasta"
    assert rejected.heard[1].startswith("All right. What is this?")


@pytest.mark.parametrize("line, kind", [("skip", "skip"), ("don't know", "dont_know"), ("undo", "undo"),
                                        ("quit", "quit"), ("none", "absent")])
def test_ending_commands_come_back_as_the_outcome(scene, line, kind):
    outcome = converse(ListTeacher([line]), prompt(scene, DemoQuery("fruit")), AnswerParser(CONCEPTS),
                       VirtualClock())
    assert outcome.kind == kind and outcome.lines == [line]


def test_end_of_input_is_quit_and_a_late_answer_counts_as_none(scene):
    assert converse(ListTeacher([]), prompt(scene, LabelQuery(0)), AnswerParser(CONCEPTS), VirtualClock()).kind \
        == "quit"
    clock = VirtualClock(10.0)
    slow = ListTeacher(["a fruit"], clock, delay=6.0)
    outcome = converse(slow, prompt(scene, LabelQuery(0), deadline=15.0), AnswerParser(CONCEPTS), clock)
    assert (outcome.kind, outcome.value, outcome.raw) == ("late", None, "a fruit")
    assert outcome.seconds == pytest.approx(6.0)
    quick = ListTeacher(["a fruit"], VirtualClock(10.0), delay=4.0)
    assert converse(quick, prompt(scene, LabelQuery(0), deadline=15.0), AnswerParser(CONCEPTS), quick.clock).kind \
        == "answer"


def test_a_feature_answer_is_read_against_the_tree(scene):
    from dialog.language.feature_tree import FeatureTree

    tree = FeatureTree(("colour.red", "colour.green", "size.length", "weight"),
                       [("object/colour", ""), ("object/colour", ""), ("object/size", ""), ("object", "")])
    outcome = converse(ListTeacher(["1.9", "ignore 1.1"]), prompt(scene, FeatureQuery(), tree=tree),
                       AnswerParser(CONCEPTS), VirtualClock())
    assert (outcome.kind, outcome.value) == ("answer", (2, 3))
    assert outcome.note == "mode=ignore"


def test_a_teacher_sending_only_noise_is_eventually_skipped(scene):
    teacher = ListTeacher(["zzz"] * 500)
    outcome = converse(teacher, prompt(scene, LabelQuery(0)), AnswerParser(CONCEPTS), VirtualClock())
    assert outcome.kind == "skip" and len(outcome.lines) == 200
