"""The thesis's chapter-6 ending (issue 39): an episode runs until its budget is spent, with a bound in turns."""

import pytest

from dialog.experiments.episodes import series_from_transcript
from dialog.experiments.report import turns_used
from dialog.experiments.suite import SuiteError, load_suite
from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.teachers.scripted import OracleTeacher
from dialog.transcripts.jsonl import TranscriptWriter, read_session, read_transcript
from learning.actions import FeatureQuery, LabelQuery
from learning.strategies import make_strategy
from tests.dialog.fakes import FakeEnvironment, ScriptedStrategy

COSTS = {"label": 2, "demo": 2, "feature": 1, "none": 0}


def play(tmp_path, strategy, **config):
    config = EpisodeConfig(**config)
    rngs = episode_generators(config.seed)
    with TranscriptWriter(tmp_path / "t.jsonl") as transcript:
        result = DialogManager(FakeEnvironment(), OracleTeacher(rngs["teacher"]), strategy, config, transcript,
                               rngs, say=lambda _: None).run()
    return result, read_transcript(tmp_path / "t.jsonl")


def test_the_episode_ends_after_the_turn_in_which_the_budget_can_pay_for_no_question(tmp_path):
    # budget 5, labels cost 2 and the feature query 1: after the feature query and two labels 0 is left
    strategy = ScriptedStrategy([FeatureQuery(), LabelQuery(0), LabelQuery(1)])
    result, records = play(tmp_path, strategy, turns=50, budget=5, costs=COSTS, until_budget_spent=True)
    assert len(records) == 3 and result.completed == 3 and result.ended == "budget"
    assert records[-1]["budget_left"] == 0


def test_budget_left_that_no_question_kind_can_use_counts_as_spent(tmp_path):
    # budget 4.5, labels at 2 each: two labels leave 0.5, which pays for no kind (feature 1): the episode ends
    result, records = play(tmp_path, make_strategy("active"), turns=50, budget=4.5, costs=COSTS,
                           until_budget_spent=True)
    assert result.ended == "budget" and len(records) == 2
    assert [r["action"]["kind"] for r in records] == ["label", "label"] and records[-1]["budget_left"] == 0.5


def test_a_feature_query_still_affordable_keeps_the_episode_going(tmp_path):
    strategy = ScriptedStrategy([LabelQuery(0), LabelQuery(1)])  # then quiet, with 1 left for the feature query
    result, records = play(tmp_path, strategy, turns=8, budget=5, costs=COSTS, until_budget_spent=True)
    assert result.ended == "bound" and len(records) == 8


def test_a_strategy_that_stays_quiet_forever_stops_at_the_bound_and_is_counted(tmp_path):
    result, records = play(tmp_path, ScriptedStrategy([]), turns=12, budget=40, until_budget_spent=True)
    assert len(records) == 12 and result.ended == "bound" and result.budget_spent == 0
    episode = {"series": series_from_transcript(records), "ended": result.ended}
    assert turns_used([episode]) == {"turns_mean": 12.0, "turns_median": 12.0, "at_bound": 1}


def test_without_the_rule_the_turns_end_the_episode(tmp_path):
    strategy = ScriptedStrategy([LabelQuery(0), LabelQuery(1)])
    result, records = play(tmp_path, strategy, turns=6, budget=4, costs=COSTS)
    assert len(records) == 6 and result.ended == "turns"


def test_the_header_names_the_rule_only_when_it_is_on(tmp_path):
    play(tmp_path / "on", ScriptedStrategy([]), turns=2, budget=4, until_budget_spent=True)
    play(tmp_path / "off", ScriptedStrategy([]), turns=2, budget=4)
    assert read_session(tmp_path / "on" / "t.jsonl")[0]["until_budget_spent"] is True
    assert "until_budget_spent" not in read_session(tmp_path / "off" / "t.jsonl")[0]


def test_chapter_6_conditions_end_on_the_budget_with_a_bound_of_ten_budgets():
    for name in ("ch6-static", "ch6-dynamic"):
        for condition in load_suite(name).conditions:
            if condition.name.endswith("-capped"):
                assert not condition.until_budget_spent
                continue
            assert condition.until_budget_spent and condition.turns == 10 * condition.budget, condition


def test_a_bad_until_budget_spent_is_one_message(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('name = "bad"\nstrategies = ["active"]\ncheckpoints = [1]\n[[condition]]\nname = "c"\n'
                    'budget = 4\nturns = 40\nchange_every = 5\nuntil_budget_spent = "yes"\n')
    with pytest.raises(SuiteError, match="'until_budget_spent' must be true or false"):
        load_suite(path)


def test_the_docs_table_gives_turns_used_and_the_bound_count_where_the_budget_ends_the_episode():
    from dialog.experiments.doc_tables import results_table

    def row(strategy, at_bound):
        pooled = {"mean": 0.8, "error": 0.01, "episodes": 5, "questions": 40.0, "demo_share": 0.5,
                  "turns_mean": 155.0, "turns_median": 140.0, "at_bound": at_bound}
        return {"strategy": strategy, "at": 40, "pooled": pooled}

    condition = {"name": "static", "budget": 40, "turns": 400, "seconds": None, "change_every": 5,
                 "objects_per_scene": 55, "teacher": {}, "until_budget_spent": True}
    capped = condition | {"name": "static-capped", "turns": 120, "until_budget_spent": False}
    table = results_table({"conditions": [condition | {"strategies": [row("dt-iros", 2)]},
                                          capped | {"strategies": [row("dt-iros", 0)]}],
                           "axis": "questions", "data_seeds": [0], "datasets": 5, "seeds": [0]})
    assert "`static`: budget 40, until the budget is spent (bound 400 turns)" in table
    assert "`static-capped`: budget 40, 120 turns" in table
    assert "| dt-iros | 40.0 q, 50%, 155 / 140 turns, 2 at the bound | 40.0 q, 50% |" in table


def test_a_budget_that_pays_for_no_question_is_refused_before_any_turn(tmp_path):
    from dialog.settings import EpisodeSettings
    from learning.errors import SettingsError
    with pytest.raises(SettingsError, match="pays for no question"):
        EpisodeSettings(budget=0.5, costs=COSTS, until_budget_spent=True)
    EpisodeSettings(budget=0.5, costs=COSTS)  # a capped episode may stay quiet for its turns
    path = tmp_path / "poor.toml"
    path.write_text('name = "poor"\nstrategies = ["active"]\ncheckpoints = [1]\n[[condition]]\nname = "c"\n'
                    'budget = 0\nturns = 40\nchange_every = 5\nuntil_budget_spent = true\n')
    with pytest.raises(SuiteError, match="condition 'c': until_budget_spent: a budget of 0 pays for no question"):
        load_suite(path)
