"""The teaching loop with a fake world and a scripted teacher."""

import io
import json

import numpy as np
import pytest

from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.teachers.scripted import OracleTeacher
from dialog.transcripts.jsonl import TranscriptWriter, read_transcript
from learning.strategies import make_strategy
from tests.dialog.fakes import FakeEnvironment, QuittingTeacher


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
    result, _, records = run_episode(tmp_path, "passive", teacher=LineTeacher(["there is none"] * 3), turns=3,
                                     budget=10)
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


# -- the full loop: every action kind, budget rules, real time, undo, resume ------------------------------------
from dialog.clock import VirtualClock  # noqa: E402
from dialog.teachers.scripted import ScriptedTeacher  # noqa: E402
from dialog.transcripts.jsonl import read_session  # noqa: E402
from learning.actions import DemoQuery, FeatureQuery, LabelQuery, NoQuery  # noqa: E402
from tests.dialog.fakes import PantryEnvironment, ScriptedStrategy  # noqa: E402


class LineTeacher:
    """Answers every question with the next of the given lines; None (end of input) when they run out."""

    def __init__(self, lines):
        self.lines, self.heard = list(lines), []

    def show(self, prompt):
        pass

    def listen(self, prompt, deadline):
        return self.lines.pop(0) if self.lines else None

    def tell(self, text):
        self.heard.append(text)


def manager_for(path, env, teacher, strategy, clock=None, **config):
    config = EpisodeConfig(**config)
    rngs = episode_generators(config.seed)
    return DialogManager(env, teacher, strategy, config, TranscriptWriter(path), rngs, say=lambda _: None,
                         clock=clock)


def test_every_action_kind_is_realised_and_recorded(tmp_path):
    actions = [FeatureQuery(), DemoQuery("fruit"), LabelQuery(1), NoQuery(), FeatureQuery(), DemoQuery("snack")]
    teacher = LineTeacher(["colour", "ignore f3", "number 3", "a snack"])
    manager = manager_for(tmp_path / "t.jsonl", FakeEnvironment(), teacher, ScriptedStrategy(actions), turns=6,
                          budget=6, change_every=10)
    result = manager.run()
    header, records = read_session(tmp_path / "t.jsonl")
    assert header["strategy"] == "scripted" and header["turns"] == 6 and header["format"] == "teachbot-transcript"
    kinds = [r["action"]["kind"] for r in records]
    assert kinds == ["feature", "demo", "label", "none", "none", "none"]
    assert records[0]["answer"]["lines"] == ["colour", "ignore f3"] and records[0]["answer"]["parsed"] == ["f1", "f2"]
    assert "I don't know 'colour'" in teacher.heard[0]
    assert records[0]["model"]["features_in_use"] == 2 and manager.state.feature_subsets["fruit"].tolist() == [0, 1]
    assert records[1]["answer"]["parsed"] == 3 and records[2]["answer"]["parsed"] == "snack"
    assert records[4]["strategy_action"] == {"kind": "feature"}  # asked at most once
    assert records[5]["strategy_action"] == {"kind": "demo", "concept": "snack"}  # budget 6 is spent
    assert "budget is spent" in records[5]["explanation"]
    for record in records:
        assert {"turn", "time", "scene_id", "action", "answer", "cost", "budget_left", "model"} <= set(record)
    assert [r["budget_left"] for r in records] == [4, 2, 1, 1, 1, 1]
    assert result.queries == {"label": 1, "demo": 1, "feature": 1, "none": 3}


def test_undo_takes_back_the_last_answer(tmp_path):
    actions = [LabelQuery(0), LabelQuery(1), LabelQuery(2)]
    teacher = LineTeacher(["a fruit", "undo", "undo", "a snack", "why", "beverage"])
    manager = manager_for(tmp_path / "t.jsonl", FakeEnvironment(), teacher, ScriptedStrategy(actions), turns=3,
                          budget=5)
    manager.run()
    records = read_session(tmp_path / "t.jsonl")[1]
    assert records[1]["undid"] == [1] and records[1]["answer"]["lines"] == ["undo", "undo", "a snack"]
    assert any("Taken back: number 1 is a fruit (turn 1); that question is not asked again unless I choose it "
               "again. Now: " in h for h in teacher.heard)  # issue 42, case 7: it read "number 1 is fruit"
    assert any("nothing left to take back" in h for h in teacher.heard)
    assert records[1]["model"]["examples"] == {"main dish": 0, "snack": 1, "fruit": 0, "beverage": 0}
    assert [e.concept for e in manager.state.examples] == ["snack", "beverage"]
    assert "Why I ask: step 3 of my script" in teacher.heard


def test_quit_ends_the_session_without_recording_the_open_question(tmp_path):
    teacher = LineTeacher(["a fruit", "quit"])
    manager = manager_for(tmp_path / "t.jsonl", FakeEnvironment(), teacher,
                          ScriptedStrategy([LabelQuery(0), LabelQuery(1)]), turns=5, budget=5)
    result = manager.run()
    assert result.quit and result.completed == 1 and len(read_transcript(tmp_path / "t.jsonl")) == 1


def test_real_time_turns_and_late_answers(tmp_path):
    clock = VirtualClock()
    teacher = ScriptedTeacher(np.random.default_rng(0), answer_delay=6.0, clock=clock)
    env = PantryEnvironment()
    manager = manager_for(tmp_path / "t.jsonl", env, teacher, make_strategy("active"), clock=clock, turns=12,
                          budget=20, change_every=3, realtime=8.0)
    manager.run()
    records = read_transcript(tmp_path / "t.jsonl")
    late = [r for r in records if r["answer"]["kind"] == "late"]
    on_time = [r for r in records if r["answer"]["kind"] == "answer"]
    assert late and on_time  # gamma delays around 6 s: some beyond the 8 s turn
    assert all(r["answer"]["seconds"] + 1.5 > 8.0 and r["answer"]["parsed"] is None for r in late)
    assert all(r["time"] >= 8.0 * (r["turn"] - 1) - 1e-9 for r in records)  # a turn never starts before its slot
    assert sum(manager.state.counts_per_concept().values()) == len(on_time)
    for record in records:  # the world changes on its own clock: every 3 x 8 s
        expected_epoch = int(record["time"] // 24.0)
        assert record["scene_id"] - records[0]["scene_id"] <= expected_epoch


def run_full(tmp_path, name, quit_at=None, resume_from=None):
    config = EpisodeConfig(turns=14, budget=18, change_every=4, seed=5)
    rngs = episode_generators(config.seed)
    env = PantryEnvironment(missing=("fruit",))
    inner = ScriptedTeacher(rngs["teacher"], mislabel_rate=0.2, dont_know_rate=0.1, answer_delay=2.0)

    inner.clock = clock = VirtualClock()
    actions = [FeatureQuery(), DemoQuery("fruit"), DemoQuery("snack")] + [LabelQuery(i % 8) for i in range(11)]
    path = tmp_path / name
    records = []
    if resume_from is not None:
        path = resume_from
        records = read_session(path, tolerate_partial_tail=True)[1]
    writer = TranscriptWriter(path, append=resume_from is not None)
    manager = DialogManager(env, QuittingTeacher(inner, quit_at), ScriptedStrategy(actions), config, writer, rngs,
                            say=lambda _: None, clock=clock)
    result = manager.run(replay=records)
    writer.close()
    return result, path, env


def test_resume_after_quit_gives_the_same_transcript_as_an_unbroken_run(tmp_path):
    _, whole, env = run_full(tmp_path, "whole.jsonl")
    assert "fruit" in env.fetched  # the absent fruit came from the pantry
    result, broken, _ = run_full(tmp_path, "broken.jsonl", quit_at=7)
    assert result.quit and len(read_transcript(broken)) == 6
    with open(broken, "a") as handle:
        handle.write('{"turn": 7, "time": 3')  # a record cut short by a crash
    resumed, _, _ = run_full(tmp_path, "unused", resume_from=broken)
    assert resumed.completed == 14 and not resumed.quit
    assert broken.read_bytes() == whole.read_bytes()


def test_a_transcript_from_another_seed_is_refused(tmp_path):
    _, whole, _ = run_full(tmp_path, "whole.jsonl")
    lines = whole.read_text().splitlines()
    record = json.loads(lines[3])
    record["model"]["examples"]["fruit"] += 5
    lines[3] = json.dumps(record)
    whole.write_text("\n".join(lines[:4]) + "\n")
    with pytest.raises(ValueError, match="turn 3: replaying the transcript gives"):
        run_full(tmp_path, "unused", resume_from=whole)


def test_observers_hear_questions_and_answers(tmp_path):
    class Recorder:
        def __init__(self):
            self.events = []

        def on_question(self, action, text, scene):
            self.events.append(("question", action.kind, text[:8]))

        def on_answer(self, action, outcome, scene):
            self.events.append(("answer", action.kind, outcome.kind))

    recorder = Recorder()
    config = EpisodeConfig(turns=2, budget=5)
    rngs = episode_generators(0)
    with TranscriptWriter(tmp_path / "t.jsonl") as transcript:
        DialogManager(FakeEnvironment(), LineTeacher(["a fruit", "none"]),
                      ScriptedStrategy([LabelQuery(0), DemoQuery("fruit")]), config, transcript, rngs,
                      say=lambda _: None, observers=[recorder]).run()
    assert recorder.events == [("question", "label", "What is "), ("answer", "label", "answer"),
                               ("question", "demo", "Can you "), ("answer", "demo", "absent")]


class FailingPantry(PantryEnvironment):
    """A pantry whose fetches come back empty-handed (no room, hidden) or with an unusable measurement."""

    def __init__(self, result):
        super().__init__(missing=("fruit",))
        self.result = result

    def fetch(self, scene, concept, rng):
        self.fetched.append(concept)
        return self.result


@pytest.mark.parametrize("result, reason", [
    ({"x": None, "kind": "peach", "reason": "the camera could not see it"}, "the camera could not see it"),
    (None, "the pantry had none"),
    ({"x": np.array([np.nan, 0.0, 0.0]), "kind": "peach"}, "my measurements of it were unusable"),
    ({"x": np.zeros(5), "kind": "peach"}, "my measurements of it were unusable"),
])
def test_a_failed_fetch_is_told_recorded_as_absent_and_the_session_goes_on(tmp_path, result, reason):
    teacher = LineTeacher(["none", "a snack", "none"])
    actions = [DemoQuery("fruit"), LabelQuery(1), DemoQuery("fruit")]
    manager = manager_for(tmp_path / "t.jsonl", FailingPantry(result), teacher, ScriptedStrategy(actions), turns=4,
                          budget=10)
    outcome = manager.run()
    records = read_transcript(tmp_path / "t.jsonl")
    assert outcome.completed == 4 and len(records) == 4
    failed = [r for r in records if "fetch_failed" in r]
    assert [r["turn"] for r in failed] == [1, 3] and all(r["answer"]["kind"] == "absent" for r in failed)
    assert all(reason in r["fetch_failed"]["reason"] and "fetched" not in r for r in failed)
    assert sum("I couldn't fetch one from the pantry" in line and reason in line for line in teacher.heard) == 2
    assert manager.state.counts_per_concept() == {"main dish": 0, "snack": 1, "fruit": 0, "beverage": 0}
    assert records[2]["scene_id"] == records[0]["scene_id"] and "fruit" in manager.state.absent_in_scene


def test_a_recorded_failed_fetch_replays_on_resume(tmp_path):
    def pantry():
        return FailingPantry({"x": None, "kind": "peach", "reason": "no room"})

    actions = [DemoQuery("fruit"), LabelQuery(1), NoQuery()]
    first = manager_for(tmp_path / "t.jsonl", pantry(), LineTeacher(["none", "a snack"]), ScriptedStrategy(actions),
                        turns=3, budget=10)
    first.run()
    first.transcript.close()
    records = read_session(tmp_path / "t.jsonl")[1]
    assert "fetch_failed" in records[0]
    resumed = DialogManager(pantry(), LineTeacher([]), ScriptedStrategy(actions), EpisodeConfig(turns=3, budget=10),
                            TranscriptWriter(tmp_path / "u.jsonl"), episode_generators(0), say=lambda _: None)
    result = resumed.run(replay=records)
    assert result.completed == 3 and resumed.state.counts_per_concept() == first.state.counts_per_concept()


def test_an_undo_before_there_is_none_to_show_still_marks_the_concept_absent(tmp_path):
    """The old trap: the turn was recorded after the answer by counting examples, so an undo in the same turn
    hid that no demonstration came back. Now the one apply records the turn from the answer itself."""
    env = FakeEnvironment(missing=("snack",))
    teacher = LineTeacher(["a fruit", "undo", "none"])
    manager = manager_for(tmp_path / "t.jsonl", env, teacher, ScriptedStrategy([LabelQuery(0), DemoQuery("snack")]),
                          turns=2, budget=5, fetch_from_pantry=False)
    manager.run()
    records = read_transcript(tmp_path / "t.jsonl")
    assert records[1]["undid"] == [1] and records[1]["answer"]["kind"] == "absent"
    assert "snack" in manager.state.absent_in_scene and manager.state.examples == ()
    assert manager.state.history == ("label", "demo") and manager.state.spent == 2 == 5 - records[1]["budget_left"]


def test_undo_takes_back_a_feature_choice_and_a_pantry_example(tmp_path):
    teacher = LineTeacher(["none", "ignore f3", "undo", "undo", "a snack"])
    env = PantryEnvironment(missing=("fruit",))
    manager = manager_for(tmp_path / "t.jsonl", env, teacher,
                          ScriptedStrategy([DemoQuery("fruit"), FeatureQuery(), LabelQuery(1)]), turns=3, budget=8)
    manager.run()
    records = read_transcript(tmp_path / "t.jsonl")
    assert records[0]["fetched"]["kind"] == "fruit-from-pantry" and records[1]["model"]["features_in_use"] == 2
    assert records[2]["undid"] == [2, 1]
    assert any("Taken back: the choice of 2 features (turn 2)" in h for h in teacher.heard)
    assert any("Taken back: the fruit from the pantry (turn 1)" in h for h in teacher.heard)
    assert all(s is None for s in manager.state.feature_subsets.values())
    assert records[2]["model"]["features_in_use"] == 3
    assert [e.concept for e in manager.state.examples] == ["snack"] and not manager.state.feature_query_asked
    assert [r["budget_left"] for r in records] == [6, 4, 7]  # the undone answers' budget (2 + 2) is given back


@pytest.mark.parametrize("first, answer, cost", [
    (LabelQuery(0), "a fruit", 1), (DemoQuery("fruit"), "1", 2), (DemoQuery("fruit"), "none", 2),
    (FeatureQuery(), "f1, f2", 2)])
def test_undo_gives_the_budget_back_for_every_query_kind(tmp_path, first, answer, cost):
    """Issue 23 case 7: an undone answer used to keep its budget spent, and an undone feature answer closed the
    feature question for good. Now the budget comes back and the feature question may be asked again."""
    from dialog.teachers.terminal import TerminalTeacher
    out = io.StringIO()
    teacher = TerminalTeacher(io.StringIO(f"{answer}\nundo\na snack\nf3\n"), out, clock=VirtualClock())
    env = PantryEnvironment(missing=("fruit",) if answer == "none" else ())
    manager = manager_for(tmp_path / "t.jsonl", env, teacher,
                          ScriptedStrategy([first, LabelQuery(1), FeatureQuery()]), turns=3, budget=8)
    manager.run()
    records = read_transcript(tmp_path / "t.jsonl")
    assert records[1]["undid"] == [1]
    assert records[1]["budget_left"] == 8 - 1  # only the second turn's label is spent
    assert records[2]["action"] == {"kind": "feature"}  # open again after a taken-back feature answer
    assert records[2]["budget_left"] == 8 - 1 - 2
    question = "Robot: " + records[1]["question"]
    assert out.getvalue().count(records[1]["question"]) == 2  # asked once, repeated once by "Taken back: ..."
    assert out.getvalue().count(question) == 1
    assert cost == records[0]["cost"]
