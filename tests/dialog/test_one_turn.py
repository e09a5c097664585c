"""Issue 25: one set of turn rules (learning/turn.py). The same seeded episode played through the library's
TeachingLoop and through the DialogManager, on the same scenes with the same answers, makes the same decisions
and reaches the same accuracy every turn."""

import numpy as np
import pytest

from dialog.episode import build_episode
from dialog.manager import episode_generators
from dialog.settings import EpisodeSettings
from dialog.teachers.scripted import OracleTeacher
from dialog.transcripts.jsonl import TranscriptWriter, read_transcript
from learning import TeachingLoop
from learning.actions import LabelQuery, NoQuery
from learning.evaluation import accuracy
from learning.synthetic import SyntheticTask, random_state
from learning.turn import admissible, scene_due
from tests.dialog.fakes import CONCEPTS, FakeEnvironment


class RecordingEnvironment(FakeEnvironment):
    """The fake world, keeping every scene and the test set it hands out."""

    def __init__(self):
        super().__init__(objects=8)
        self.scenes, self.test = [], None

    def next_scene(self, rng):
        scene = super().next_scene(rng)
        self.scenes.append(scene)
        return scene

    def test_set(self, n_scenes, rng):
        self.test = super().test_set(n_scenes, rng)
        return self.test


def the_loop_answer(record, scene):
    """The loop's answer to the manager's question: labels from the scene's truth, the rest as the teacher gave."""
    kind, answer = record["action"]["kind"], record["answer"]
    if kind == "label":
        truth = scene.truth.concepts[record["action"]["object"] - 1]
        assert answer["parsed"] == truth  # the oracle answered from the same truth
        return truth
    if kind == "demo":
        return None if answer["parsed"] is None else int(answer["parsed"]) - 1
    if kind == "feature":
        return list(answer["parsed"]) if answer["parsed"] else None
    return None


@pytest.mark.parametrize("strategy", ["dt-task", "active", "random", "hfs-active"])
def test_the_library_loop_and_the_dialog_make_the_same_decisions(tmp_path, strategy):
    settings = EpisodeSettings(task="pack-lunchbox", strategy=strategy, seed=3, turns=14, budget=12, change_every=4)
    rngs = episode_generators(settings.seed)
    environment = RecordingEnvironment()
    with TranscriptWriter(tmp_path / "t.jsonl") as transcript:
        build_episode(settings, environment, OracleTeacher(rngs["teacher"]), transcript, rngs=rngs,
                      say=lambda _: None).run()
    records = read_transcript(tmp_path / "t.jsonl")
    scenes = {scene.scene_id: scene for scene in environment.scenes}
    test_X, test_y = environment.test

    loop = TeachingLoop(list(CONCEPTS), strategy, budget=12, turns=14, change_every=4,
                        seed=episode_generators(settings.seed)["strategy"], feature_names=environment.feature_names)
    for record in records:
        if loop.scene_due:
            loop.observe(scenes[record["scene_id"]].X)
        query = loop.ask()
        assert query.kind == record["action"]["kind"], f"turn {record['turn']}"
        if query.kind == "label":
            assert query.object == record["action"]["object"] - 1
        if query.kind == "demo":
            assert query.concept == record["action"]["concept"]
        assert query.cost == record["cost"]
        loop.tell(the_loop_answer(record, scenes[record["scene_id"]]))
        assert loop.budget_left == pytest.approx(record["budget_left"])
        assert round(accuracy(loop.predict(test_X), test_y), 6) == record["accuracy"], f"turn {record['turn']}"
    assert loop.done and len(records) == 14 and len(environment.scenes) == 4  # scenes at turns 1, 5, 9, 13


def test_the_rules_refuse_what_cannot_be_asked_with_a_reason():
    task = SyntheticTask()
    state = random_state(task, 12, 6, np.random.default_rng(0), budget=10.0)
    assert admissible(state, NoQuery()) == (NoQuery(), "")
    assert admissible(state, LabelQuery(2))[0] == LabelQuery(2)
    action, reason = admissible(state, LabelQuery(6))
    assert action == NoQuery() and reason.startswith("Nothing to ask: label query object 6 is not an object")
    state.place_progress(turn=state.turn, spent=10.0, history=[], feature_query_asked=True)
    assert admissible(state, LabelQuery(2)) == (NoQuery(), "Nothing to ask: the budget is spent (10 of 10).")
    assert scene_due(0, 4, None) and not scene_due(3, 4, 0) and scene_due(4, 4, 0)
