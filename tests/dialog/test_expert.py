"""Expert mode (issue 8 phase 2): the ExpertStrategy in the real manager loop, the scripted expert's rules,
and the demonstration files it writes. Fake world, no simulator."""

import math

import numpy as np
import pytest

from dialog.expert.episode import ExpertQuit, ExpertSettings, ExpertStrategy, run_expert_episode
from dialog.expert.scripted import ScriptedExpertChooser, paced_budget
from learning.actions import DEFAULT_COSTS
from learning.decision.candidates import expected_decision_features
from learning.irl.demonstrations import load_episodes
from tests.dialog.fakes import FakeEnvironment
from tests.scripts import load_script

TRAINING = dict(budget=15.0, turns=30, change_every=10)  # thesis §7.4.1


def scripted_episode(tmp_path, seed, chooser=None, **overrides):
    settings = ExpertSettings(seed=seed, **{**TRAINING, **overrides})
    return run_expert_episode(settings, chooser or ScriptedExpertChooser(), tmp_path / f"run{seed}",
                              environment=FakeEnvironment(objects=10), say=lambda text: None)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_scripted_expert_follows_its_documented_rules(tmp_path, seed):
    outcome = scripted_episode(tmp_path, seed)
    turns = outcome.episode.turns
    chosen = [turn.kinds[turn.chosen] for turn in turns]
    assert "feature" in chosen[:5]  # FSQ within the first five turns
    costs = np.cumsum([DEFAULT_COSTS[kind] for kind in chosen])
    assert costs[-1] <= TRAINING["budget"]  # never over budget
    for t, spent in enumerate(costs, start=1):  # paced: at most B (t + h) / T by turn t (FSQ may run ahead by 2)
        assert spent <= paced_budget(15.0, 30, t, 3.0) + DEFAULT_COSTS["feature"] + 1e-9
    for scene in range(3):  # every scene gets part of the budget, none gets it all
        window = chosen[scene * 10:(scene + 1) * 10]
        assert any(kind != "none" for kind in window)
    assert costs[9] < TRAINING["budget"]
    assert chosen.count("label") > chosen.count("demo") + chosen.count("feature")  # cheap queries first
    again = scripted_episode(tmp_path / "again", seed)
    assert [t.chosen for t in again.episode.turns] == [t.chosen for t in turns]  # seeded


def test_recorded_features_are_what_the_dt_strategy_computes(tmp_path):
    from learning.strategies import make_strategy

    dt = make_strategy("dt-task-env-v1")  # the eleven features the expert records

    class Checking(ScriptedExpertChooser):
        checked = 0

        def choose(self, view):
            dt.choose(view.state, np.random.default_rng(0))
            assert dt.last_candidates.actions == view.candidates.actions
            np.testing.assert_array_equal(dt.last_candidates.expected, view.candidates.expected)
            Checking.checked += 1
            return super().choose(view)

    outcome = scripted_episode(tmp_path, 4, Checking(), turns=12)
    assert Checking.checked >= 10
    saved = load_episodes(outcome.demonstration)[0]
    assert saved.metadata["engine"] == "fast" and saved.metadata["budget"] == 15.0
    first = saved.turns[0]
    assert first.kinds[-1] == "none" and first.labels[-1] == "no query"
    quiet_row = first.phi[-1]  # eq. 7.1: no query is scored at s_{t+1} too, so time passes whatever is asked
    assert all(math.isclose(quiet_row[5], row[5]) for row in first.phi[:-1])
    assert quiet_row[6] > 0 and all(row[6] == 0 for row in first.phi[:-1])  # only a quiet turn adds quiet time


def test_quitting_keeps_the_turns_so_far(tmp_path):
    class QuitsAtFour(ScriptedExpertChooser):
        def choose(self, view):
            if view.turn == 4:
                raise ExpertQuit()
            return super().choose(view)

    outcome = scripted_episode(tmp_path, 5, QuitsAtFour())
    assert outcome.result.quit and len(outcome.episode.turns) == 3
    assert len(load_episodes(outcome.demonstration)[0].turns) == 3
    with pytest.raises(ValueError, match="already exists"):
        scripted_episode(tmp_path, 5)


def test_an_expert_strategy_refuses_a_choice_that_is_not_a_candidate():
    from learning.actions import LabelQuery
    from learning.state import LearningState

    class Wrong:
        name = "wrong"

        def choose(self, view):
            return LabelQuery(99)

    state = LearningState(("a", "b"), ("f1", "f2"), 5, 10)
    state.observe_scene(1, np.array([[0.0, 1.0], [1.0, 0.0]]))
    with pytest.raises(ValueError, match="not a candidate"):
        ExpertStrategy(Wrong()).choose(state, np.random.default_rng(0))
    assert len(expected_decision_features(state).actions) == 6  # 2 DQ, 2 LQ, FSQ, no query


def test_person_commands_are_parsed_and_bad_ones_explained(tmp_path):
    import io

    from dialog.expert.terminal import PersonChooser

    typed = io.StringIO("help\nbogus\nLQ 99\nDQ pizza\nFSQ\nDQ fruit\n1\nnone\n")
    shown = io.StringIO()
    outcome = scripted_episode(tmp_path, 6, PersonChooser(typed, shown), turns=6)
    text = shown.getvalue()
    assert "'bogus' is not a command" in text and "There is no object 99" in text and "name one concept" in text
    chosen = [t.labels[t.chosen] for t in outcome.episode.turns]
    assert chosen[:4] == ["FSQ", "DQ(fruit)", "LQ(object 1)", "no query"]
    assert outcome.result.quit and len(load_episodes(outcome.demonstration)[0].turns) == 4  # end of input = quit


def test_the_scripted_expert_strategy_asks_what_expert_mode_asks(tmp_path):
    """One plan in two places: `scripted-expert` in the manager = `teachbot expert --expert scripted`."""
    from dialog.manager import DialogManager, episode_generators
    from dialog.teachers.scripted import ScriptedTeacher
    from dialog.transcripts.jsonl import TranscriptWriter, read_transcript
    from learning.strategies import make_strategy

    recorded = scripted_episode(tmp_path, 7)
    settings = ExpertSettings(seed=7, strategy="scripted-expert", **TRAINING)
    rngs = episode_generators(settings.seed)
    teacher = ScriptedTeacher(rngs["teacher"], 0.0, 0.0)
    with TranscriptWriter(tmp_path / "strategy.jsonl") as transcript:
        result = DialogManager(FakeEnvironment(objects=10), teacher, make_strategy("scripted-expert"),
                               settings.config(), transcript, rngs, say=lambda text: None).run()
    records = read_transcript(tmp_path / "strategy.jsonl")
    kinds = [record["action"]["kind"] for record in records]
    assert kinds == [turn.kinds[turn.chosen] for turn in recorded.episode.turns]
    assert result.accuracy == pytest.approx(recorded.result.accuracy)
    assert "feature" in kinds[:5] and kinds.count("label") > kinds.count("demo")


def test_shipped_demonstrations_are_the_suite_episodes_of_the_expert_strategy(tmp_path):
    """scripts/make_expert_demos.py plays the ch7-training condition on its data sets, as `regress` does."""
    from dataclasses import replace

    from dialog.experiments.episodes import run_episode
    from dialog.experiments.suite import load_suite

    script = load_script("make_expert_demos")
    suite = load_suite("ch7-training")
    spec = script.episode_spec(suite, 6, suite.data_seed)
    assert (spec.dataset, spec.episode_seed, spec.data_seed) == (6 % suite.datasets, 6000 + 6 % suite.datasets, 100)
    outcome = script.make_demo(spec, tmp_path / "demos")
    saved = load_episodes(outcome.demonstration)[0]
    assert saved.name == "scripted-expert-prepare-lunch-seed6" and len(saved.turns) == 30
    assert saved.metadata["data_seed"] == 100 and saved.metadata["dataset"] == spec.dataset
    episode = run_episode(replace(spec, transcript=str(tmp_path / "suite.jsonl")))
    chosen = [turn.kinds[turn.chosen] for turn in saved.turns]
    questions = {kind: chosen.count(kind) for kind in ("label", "demo", "feature")}
    assert all(episode["series"][kind][-1] == count for kind, count in questions.items())
    assert episode["accuracy"] == pytest.approx(outcome.result.accuracy)


def test_the_expert_summary_is_words_not_a_python_dict(tmp_path, capsys):
    from dialog.cli import main
    assert main(["expert", "--expert", "scripted", "--turns", "1", "--out", str(tmp_path)]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith("Done after 1 turn: ") and "{" not in last
    assert ", 0 demonstrations, " in last or ", 1 demonstration, " in last
