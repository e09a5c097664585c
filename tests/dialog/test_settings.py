"""One frozen episode-settings dataclass, its defaults written once, and abilities checked once."""

from __future__ import annotations

import dataclasses
import io

import pytest

from dialog.cli import build_parser
from dialog.clock import VirtualClock
from dialog.episode import make_teacher
from dialog.experiments.episodes import EpisodeSpec, suite_teacher
from dialog.experiments.suite import Condition
from dialog.expert.episode import ExpertSettings
from dialog.language.questions import Questioner
from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.session import SessionSettings, session_teacher
from dialog.settings import DEFAULTS, EpisodeSettings
from dialog.teachers.conversation import OUTCOME_KINDS
from dialog.teachers.protocol import FastForwards, Teacher, checked_teacher
from dialog.teachers.scripted import OracleTeacher, ReplayTeacher, ScriptedTeacher
from dialog.teachers.terminal import TerminalTeacher
from dialog.transcripts.jsonl import TranscriptWriter
from dialog.transcripts.records import ANSWER_KINDS
from learning.actions import ACTION_KINDS, DEFAULT_COSTS, DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.errors import SettingsError
from learning.state import LearningState
from learning.strategies import make_strategy
from tests.dialog.fakes import FakeEnvironment, PantryEnvironment

EPISODE_OPTIONS = ("task", "kitchen", "seed", "turns", "budget", "change_every")


@pytest.mark.parametrize("command", ["demo", "teach"])
def test_command_line_defaults_are_the_settings_defaults(command):
    args = build_parser().parse_args([command])
    assert {name: getattr(args, name) for name in EPISODE_OPTIONS} == \
        {name: getattr(DEFAULTS, name) for name in EPISODE_OPTIONS}


def test_expert_defaults_are_the_thesis_training_condition_and_reach_the_command_line():
    expert = ExpertSettings()
    assert (expert.task, expert.budget, expert.turns, expert.change_every) == ("prepare-lunch", 15.0, 30, 10)
    args = build_parser().parse_args(["expert"])
    assert {name: getattr(args, name) for name in EPISODE_OPTIONS} == \
        {name: getattr(expert, name) for name in EPISODE_OPTIONS}
    assert args.costs == expert.costs == DEFAULT_COSTS


def test_the_manager_config_has_the_same_defaults():
    config, made = EpisodeConfig(), DEFAULTS.config()
    assert config == made
    assert (config.turns, config.budget, config.change_every, config.seed) == (30, 40.0, 5, 0)


@pytest.mark.parametrize("kind", [EpisodeSettings, SessionSettings, ExpertSettings])
def test_settings_are_frozen(kind):
    settings = kind()
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.turns = 3
    assert dataclasses.replace(settings, turns=3).turns == 3


@pytest.mark.parametrize(("values", "named"), [
    ({"turns": 0}, "turns must be at least 1"), ({"turns": 2.5}, "turns"), ({"budget": -1}, "budget"),
    ({"budget": "lots"}, "budget"), ({"change_every": 0}, "change-every"), ({"realtime": -2.0}, "realtime"),
    ({"seed": -1}, "seed"), ({"task": ""}, "task"), ({"fetch_from_pantry": "yes"}, "fetch_from_pantry"),
    ({"costs": {"label": 1}}, "costs must give a cost"), ({"costs": {**DEFAULT_COSTS, "demo": -2}}, "costs"),
])
def test_bad_values_are_refused_naming_the_option(values, named):
    with pytest.raises(SettingsError, match=named):
        EpisodeSettings(**values)
    with pytest.raises(SettingsError, match=named):
        SessionSettings(**values)


def test_session_and_expert_settings_check_their_own_fields_too():
    with pytest.raises(SettingsError, match="teacher 'robot'"):
        SessionSettings(teacher={"kind": "robot"})
    with pytest.raises(SettingsError, match="mislabel_rate must be between 0 and 1"):
        ExpertSettings(mislabel_rate=1.5)


def test_an_old_header_without_the_newer_fields_gets_the_defaults():
    header = {"task": "pack-lunchbox", "kitchen": "kitchen-2", "strategy": "dt-task", "seed": 3, "turns": 12,
              "budget": 20, "change_every": 4, "teacher": {"kind": "scripted", "mislabel_rate": 0.1}}
    settings = SessionSettings.from_header(header, "old.jsonl")
    assert (settings.kitchen, settings.seed, settings.turns, settings.budget) == ("kitchen-2", 3, 12, 20)
    assert settings.costs == DEFAULT_COSTS and settings.fetch_from_pantry and settings.realtime is None
    config = settings.config("pictures")
    assert (config.turns, config.budget, config.change_every, config.seed, config.pictures) == (12, 20, 4, 3,
                                                                                                  "pictures")


def test_a_suite_episode_has_the_same_settings():
    spec = EpisodeSpec(suite="s", task="pack-lunchbox", kitchen="kitchen-1", strategy="passive",
                       condition=Condition("tight", budget=8.0, turns=12, change_every=3), dataset=2, seed=1,
                       costs=tuple(sorted(DEFAULT_COSTS.items())), teacher=(), transcript="t.jsonl")
    settings = spec.settings()
    assert isinstance(settings, EpisodeSettings)
    assert (settings.seed, settings.turns, settings.budget, settings.change_every) == (1002, 12, 8.0, 3)
    assert settings.config().costs == DEFAULT_COSTS


# -- optional abilities, checked once ------------------------------------------------------------------------------
class Recorder:
    """An observer of turns only; an attribute that is not a method is no handler."""

    on_scene = "not callable"

    def __init__(self):
        self.turns = []

    def on_turn(self, record, scene):
        self.turns.append(record["turn"])


def _manager(tmp_path, env, teacher=None, observers=(), name="t.jsonl"):
    rngs = episode_generators(0)
    return DialogManager(env, teacher or OracleTeacher(rngs["teacher"]), make_strategy("passive"),
                         EpisodeConfig(turns=2, budget=4), TranscriptWriter(tmp_path / name), rngs,
                         say=lambda _: None, observers=observers)


class BareEnvironment:
    """Only what every environment has: concepts, features, scenes, pointing, a test set."""

    def __init__(self):
        self.inner = FakeEnvironment()
        self.concepts, self.feature_names = self.inner.concepts, self.inner.feature_names

    def next_scene(self, rng):
        return self.inner.next_scene(rng)

    def point_at(self, scene, index):
        return self.inner.point_at(scene, index)

    def test_set(self, n_scenes, rng):
        return self.inner.test_set(n_scenes, rng)


def test_an_environment_without_the_optional_abilities(tmp_path):
    env = BareEnvironment()
    manager = _manager(tmp_path, env)
    assert not manager.can_fetch and manager.test_scenes == 4
    other = _manager(tmp_path, FakeEnvironment(), name="other.jsonl")
    assert other.test_scenes == FakeEnvironment.test_scenes
    other.transcript.close()
    manager.run()
    manager.transcript.close()
    assert env.inner.scene_count == 4 + 1  # the default test set of four scenes, then one scene
    questioner = Questioner(env, LearningState(env.concepts, env.feature_names, 4, 2), pictures=str(tmp_path))
    assert questioner.locations is None and questioner.viewpoint is None and not questioner.draws_pictures
    assert questioner.relevant_features is None


def test_a_pantry_environment_can_fetch(tmp_path):
    assert _manager(tmp_path, PantryEnvironment()).can_fetch


def test_observers_get_only_the_events_they_handle(tmp_path):
    recorder = Recorder()
    manager = _manager(tmp_path, FakeEnvironment(), observers=[recorder])
    manager.run()
    manager.transcript.close()
    assert recorder.turns == [1, 2]


def test_one_teacher_protocol():
    rng = episode_generators(0)["teacher"]
    scripted = ScriptedTeacher(rng)
    assert checked_teacher(scripted) is scripted
    with pytest.raises(TypeError, match="is not a teacher"):
        checked_teacher(object())


def test_one_teacher_factory_for_every_kind(tmp_path):
    rng = episode_generators(0)["teacher"]
    scripted = make_teacher("scripted", rng=rng, mislabel_rate=0.25, answer_delay=1)
    assert isinstance(scripted, ScriptedTeacher) and scripted.mislabel_rate == 0.25
    assert isinstance(make_teacher("oracle", rng=rng), OracleTeacher)
    assert isinstance(make_teacher("terminal", input_stream=io.StringIO(""), output_stream=io.StringIO()),
                      TerminalTeacher)
    recorded = tmp_path / "old.jsonl"
    recorded.write_text('{"turn": 1, "answer": {"lines": ["a fruit"]}}\n')
    assert isinstance(make_teacher("replay", transcript=recorded), ReplayTeacher)
    for teacher in (scripted, make_teacher("replay", transcript=recorded)):
        assert isinstance(teacher, Teacher)
    assert isinstance(scripted, FastForwards)


@pytest.mark.parametrize(("kind", "options", "message"), [
    ("robot", {}, "teacher 'robot' is not one of terminal, scripted, oracle, replay"),
    ("oracle", {"mislabel_rate": 0.1}, "an? oracle teacher does not take the options mislabel_rate; accepted: none"),
    ("scripted", {"patience": 3}, "does not take the options patience; accepted: mislabel_rate"),
    ("replay", {}, "needs the transcript"),
    ("scripted", {"mislabel_rate": 2}, "mislabel rate must be between 0 and 1"),
])
def test_the_teacher_factory_refuses_bad_options_naming_them(kind, options, message):
    with pytest.raises(SettingsError, match=message):
        make_teacher(kind, rng=episode_generators(0)["teacher"], **options)


def test_suites_and_sessions_build_their_teachers_with_the_factory():
    rng = episode_generators(0)["teacher"]
    assert isinstance(suite_teacher({"kind": "oracle"}, rng), OracleTeacher)
    assert suite_teacher({"dont_know_rate": 0.5}, rng).dont_know_rate == 0.5
    with pytest.raises(SettingsError, match="accepted: kind = 'scripted' or 'oracle'"):
        suite_teacher({"kind": "terminal"}, rng)
    settings = SessionSettings(teacher={"kind": "scripted", "feature_quality": 0.5})
    teacher = session_teacher(settings, episode_generators(0), VirtualClock())
    assert isinstance(teacher, ScriptedTeacher) and teacher.feature_quality == 0.5


def test_action_and_outcome_kinds_are_literals():
    assert ACTION_KINDS == ("label", "demo", "feature", "none") == tuple(DEFAULT_COSTS)
    assert {LabelQuery(0).kind, DemoQuery("fruit").kind, FeatureQuery().kind, NoQuery().kind} == set(ACTION_KINDS)
    assert set(ANSWER_KINDS) <= set(OUTCOME_KINDS)
