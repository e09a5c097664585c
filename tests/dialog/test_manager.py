"""The teaching loop with a fake world and a scripted teacher."""

import json

import pytest

from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.teachers import Answer, OracleTeacher
from dialog.transcript import TranscriptWriter, read_transcript
from learning.strategies import make_strategy
from tests.dialog.fakes import FakeEnvironment


def run_episode(tmp_path, strategy="active", teacher=None, **config):
    config = EpisodeConfig(**config)
    rngs = episode_generators(config.seed)
    env = FakeEnvironment()
    teacher = teacher or OracleTeacher(rngs["teacher"])
    with TranscriptWriter(tmp_path / "t.jsonl") as transcript:
        result = DialogManager(env, teacher, make_strategy(strategy), config, transcript, rngs,
                               say=lambda _: None).run()
    return result, env, read_transcript(tmp_path / "t.jsonl")


@pytest.mark.parametrize("strategy", ["active", "passive"])
def test_budget_is_respected_and_every_turn_recorded(tmp_path, strategy):
    result, _, records = run_episode(tmp_path, strategy, turns=20, budget=9, change_every=4)
    assert len(records) == 20 and [r["turn"] for r in records] == list(range(1, 21))
    assert result.budget_spent <= 9
    assert all(r["budget_left"] >= 0 for r in records)
    assert records[-1]["action"]["kind"] == "none"  # the budget ran out before the end
    assert sum(result.queries.values()) == 20


def test_scene_changes_every_r_turns(tmp_path):
    _, env, records = run_episode(tmp_path, turns=12, budget=50, change_every=5)
    scene_ids = [r["scene_id"] for r in records]
    assert len(set(scene_ids[0:5])) == 1 and len(set(scene_ids[5:10])) == 1 and scene_ids[4] != scene_ids[5]
    assert env.scene_count == 3 + 3  # three test scenes, then a scene at turns 1, 6 and 11


def test_label_queries_point_first_and_learning_helps(tmp_path):
    result, env, records = run_episode(tmp_path, turns=16, budget=16, change_every=4)
    labelled = [r for r in records if r["action"]["kind"] == "label"]
    assert len(env.pointed) == len(labelled) == 16
    assert all(r["gesture"] == {"reached": True} for r in labelled)
    assert result.accuracy > 0.8
    assert records[-1]["accuracy"] == pytest.approx(result.accuracy, abs=1e-6)


def test_a_demo_of_an_absent_concept_adds_nothing(tmp_path):
    class NothingHere:
        def answer(self, action, question, scene):
            return Answer("there is none", None)

    result, _, records = run_episode(tmp_path, "passive", teacher=NothingHere(), turns=3, budget=10)
    assert all(sum(r["model"]["examples"].values()) == 0 for r in records)
    assert result.budget_spent == 6


def test_transcript_is_json_lines_flushed_each_turn(tmp_path):
    path = tmp_path / "t.jsonl"
    with TranscriptWriter(path) as writer:
        writer.write({"turn": 1})
        assert json.loads(path.read_text()) == {"turn": 1}  # on disk before close


def test_unreadable_transcript_line_is_named(tmp_path):
    path = tmp_path / "bad.jsonl"
    path.write_text('{"turn": 1}\nnot json\n')
    with pytest.raises(ValueError, match="line 2 is not a JSON record"):
        read_transcript(path)


def test_bad_config_is_a_clear_error():
    with pytest.raises(ValueError, match="change-every must be at least 1"):
        EpisodeConfig(change_every=0)


def test_same_seed_gives_identical_transcripts(tmp_path):
    run_episode(tmp_path / "a", turns=10, budget=10, seed=4)
    run_episode(tmp_path / "b", turns=10, budget=10, seed=4)
    assert (tmp_path / "a" / "t.jsonl").read_bytes() == (tmp_path / "b" / "t.jsonl").read_bytes()


def test_observers_see_every_scene_and_turn(tmp_path):
    class Recorder:
        def __init__(self):
            self.scenes, self.turns = [], []

        def on_scene(self, scene):
            self.scenes.append(scene.scene_id)

        def on_turn(self, record, scene):
            self.turns.append((record["turn"], scene.scene_id))

    recorder = Recorder()
    config = EpisodeConfig(turns=6, budget=6, change_every=3)
    rngs = episode_generators(0)
    with TranscriptWriter(tmp_path / "t.jsonl") as transcript:
        DialogManager(FakeEnvironment(), OracleTeacher(rngs["teacher"]), make_strategy("active"), config,
                      transcript, rngs, say=lambda _: None, observers=[recorder]).run()
    assert len(recorder.scenes) == 2 and [t for t, _ in recorder.turns] == [1, 2, 3, 4, 5, 6]
    assert recorder.turns[3][1] == recorder.scenes[1]
