"""Scripted teachers: seeded noise models that answer in plain words; the replay teacher."""

import numpy as np
import pytest

from dialog.clock import VirtualClock
from dialog.language.feature_tree import FeatureTree
from dialog.language.parsing import AnswerParser
from dialog.language.questions import Prompt
from dialog.teachers.scripted import OracleTeacher, ReplayTeacher, ScriptedTeacher
from learning.actions import DemoQuery, FeatureQuery, LabelQuery
from learning.errors import SettingsError
from tests.dialog.fakes import CONCEPTS, FakeEnvironment

NAMES = ("colour.red", "size.length", "weight", "arm.joint1", "hand.x")
GROUPS = [("object/colour", ""), ("object/size", ""), ("object", ""), ("robot/arm", ""), ("robot/hand", "")]


@pytest.fixture
def scene():
    return FakeEnvironment(objects=8).next_scene(np.random.default_rng(0))


def prompt(scene, action, relevant=None):
    return Prompt(1, 10, 5.0, action, "?", "", scene, CONCEPTS, feature_tree=FeatureTree(NAMES, GROUPS),
                  relevant_features=relevant)


def answers(teacher, scene, action, n=400):
    parser = AnswerParser(CONCEPTS)
    out = []
    for _ in range(n):
        line = teacher.listen(prompt(scene, action), None)
        if action.kind == "label":
            out.append(parser.label(line))
        elif action.kind == "demo":
            out.append(parser.demonstration(line, scene.n_objects, action.concept))
        else:
            out.append(prompt(scene, action).feature_tree.read(line))
    return out


def test_the_oracle_answers_from_ground_truth_in_words_the_parser_reads(scene):
    oracle = OracleTeacher(np.random.default_rng(0))
    label = answers(oracle, scene, LabelQuery(2), 5)
    assert {(r.kind, r.value) for r in label} == {("answer", scene.truth.concepts[2])}
    demo = answers(oracle, scene, DemoQuery("fruit"), 20)
    assert all(r.kind == "answer" and scene.truth.concepts[r.value] == "fruit" for r in demo)
    features = answers(oracle, scene, FeatureQuery(), 3)
    assert {r.value for r in features} == {(0, 1, 2)}  # the object features (no Task.relevant_features here)
    empty = FakeEnvironment(missing=("fruit",)).next_scene(np.random.default_rng(1))
    assert answers(oracle, empty, DemoQuery("fruit"), 1)[0].kind == "absent"


def test_mislabel_and_dont_know_rates_are_what_was_asked(scene):
    teacher = ScriptedTeacher(np.random.default_rng(0), mislabel_rate=0.1, dont_know_rate=0.2)
    readings = answers(teacher, scene, LabelQuery(0), 2000)
    unsure = sum(r.kind == "dont_know" for r in readings) / len(readings)
    wrong = sum(r.kind == "answer" and r.value != scene.truth.concepts[0] for r in readings)
    answered = sum(r.kind == "answer" for r in readings)
    assert unsure == pytest.approx(0.2, abs=0.03)
    assert wrong / answered == pytest.approx(0.1, abs=0.025) and wrong == teacher.mislabels
    demos = answers(ScriptedTeacher(np.random.default_rng(4), mislabel_rate=0.3), scene, DemoQuery("fruit"), 1000)
    shown_wrong = sum(scene.truth.concepts[r.value] != "fruit" for r in demos) / len(demos)
    assert shown_wrong == pytest.approx(0.3, abs=0.05)


def test_feature_quality_trades_relevant_for_irrelevant_features(scene):
    relevant = ("colour.red", "size.length")
    perfect = ScriptedTeacher(np.random.default_rng(0), feature_quality=1.0)
    assert perfect.listen(prompt(scene, FeatureQuery(), relevant), None) == "1.1, 1.2"
    noisy = ScriptedTeacher(np.random.default_rng(0), feature_quality=0.5)
    chosen = [prompt(scene, FeatureQuery()).feature_tree.read(noisy.listen(prompt(scene, FeatureQuery(), relevant),
                                                                           None)).value for _ in range(600)]
    hits = np.mean([len({0, 1} & set(c)) / 2 for c in chosen])
    extras = np.mean([len(set(c) - {0, 1}) for c in chosen])
    assert hits == pytest.approx(0.625, abs=0.08)  # at least one relevant feature is always named
    assert extras == pytest.approx(1.0, abs=0.2)


def test_the_feature_answer_model_partial_noisy_and_dont_know(scene):
    """Issue 26 item 3: a teacher's feature answer may name only some relevant features, add irrelevant ones,
    or not know; the exact answer stays the default and is recorded as before (no new header keys)."""
    relevant = ("colour.red", "size.length", "weight", "arm.joint1")
    ask = prompt(scene, FeatureQuery(), relevant)

    def read(teacher):
        return ask.feature_tree.read(teacher.listen(ask, None)).value

    half = ScriptedTeacher(np.random.default_rng(1), feature_recall=0.5)
    picks = [set(read(half)) for _ in range(200)]
    assert all(len(p) == 2 and p <= {0, 1, 2, 3} for p in picks) and len({frozenset(p) for p in picks}) > 3
    noisy = ScriptedTeacher(np.random.default_rng(1), feature_noise=0.25)
    assert all(set(read(noisy)) == {0, 1, 2, 3, 4} for _ in range(20))  # all four and round(0.25 x 4) = 1 other
    unsure = ScriptedTeacher(np.random.default_rng(1), feature_dont_know_rate=1.0)
    assert unsure.listen(ask, None) == "I don't know"
    assert unsure.listen(prompt(scene, LabelQuery(0)), None) != "I don't know"  # only the feature question
    assert "feature_recall" not in ScriptedTeacher(np.random.default_rng(0)).options()
    assert half.options()["feature_recall"] == 0.5 and "feature_noise" not in half.options()
    with pytest.raises(SettingsError, match="not both"):
        ScriptedTeacher(np.random.default_rng(0), feature_quality=0.5, feature_recall=0.5)
    with pytest.raises(SettingsError, match="feature recall must be between 0 and 1"):
        ScriptedTeacher(np.random.default_rng(0), feature_recall=1.5)


def test_a_suite_condition_sets_its_own_feature_answer_over_the_suite_teacher(tmp_path):
    from dialog.experiments.runner import episode_specs
    from dialog.experiments.suite import SuiteError, load_suite
    suite = load_suite("ch6-static")
    specs = {spec.condition.name: dict(spec.teacher) for spec in episode_specs(suite, tmp_path)}
    assert specs["static"] == {} and specs["features-half"] == {"feature_recall": 0.5}
    assert specs["features-dont-know"] == {"feature_dont_know_rate": 1.0}
    text = open(suite.path).read().replace("feature_noise = 1.0", "feature_noise = 2.0")
    (tmp_path / "bad.toml").write_text(text)
    with pytest.raises(SuiteError, match="feature_noise"):
        load_suite(tmp_path / "bad.toml")


def test_answer_delay_is_spent_on_the_injected_clock(scene):
    clock = VirtualClock()
    teacher = ScriptedTeacher(np.random.default_rng(0), answer_delay=3.0, clock=clock)
    for _ in range(300):
        teacher.listen(prompt(scene, LabelQuery(0)), None)
    assert clock.now() / 300 == pytest.approx(3.0, rel=0.1)


def test_same_seed_same_answers_and_fast_forward_keeps_step(scene):
    def run(skip_first):
        teacher = ScriptedTeacher(np.random.default_rng(9), mislabel_rate=0.4, dont_know_rate=0.2)
        if skip_first:
            teacher.fast_forward(prompt(scene, LabelQuery(1)))
        else:
            teacher.listen(prompt(scene, LabelQuery(1)), None)
        return [teacher.listen(prompt(scene, LabelQuery(i % 8)), None) for i in range(30)]

    assert run(False) == run(True)


@pytest.mark.parametrize("options, fragment", [({"mislabel_rate": 1.5}, "mislabel rate"),
                                               ({"answer_delay": -1}, "answer delay")])
def test_bad_teacher_options_are_refused(options, fragment):
    with pytest.raises(ValueError, match=fragment):
        ScriptedTeacher(np.random.default_rng(0), **options)


def test_the_replay_teacher_gives_each_turn_its_recorded_lines(scene):
    teacher = ReplayTeacher([{"turn": 1, "answer": {"lines": ["zzz", "a fruit"]}}, {"turn": 2, "answer": {}}])
    first = prompt(scene, LabelQuery(0))
    assert [teacher.listen(first, None) for _ in range(3)] == ["zzz", "a fruit", None]
    first.turn = 2
    assert teacher.listen(first, None) is None
