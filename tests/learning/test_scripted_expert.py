"""The scripted expert as a strategy (learning.strategies.scripted_expert): its rules on a synthetic task, its
pace, its rules file, and that it decides from the learner's view alone."""

import numpy as np
import pytest

from learning.actions import DEFAULT_COSTS, DemoQuery, FeatureQuery, NoQuery
from learning.decision.candidates import expected_decision_features
from learning.state import LearningState
from learning.strategies import make_strategy
from learning.strategies.scripted_expert import (
    RULES_FILE,
    ExpertPlan,
    ExpertRules,
    ScriptedExpertStrategy,
    paced_budget,
)
from learning.synthetic import SyntheticTask, run_episode

TASK = SyntheticTask(n_features=10, n_informative=3, seed=2)
TRAINING = dict(budget=15, turns=30, change_every=10, objects=12, costs=DEFAULT_COSTS)  # thesis §7.4.1


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_the_expert_strategy_keeps_its_habits_on_a_synthetic_task(seed):
    summary = run_episode(make_strategy("scripted-expert"), TASK, np.random.default_rng(seed), **TRAINING)
    kinds = [action.kind for action in summary.actions]
    assert "feature" in kinds[:5] and kinds.count("feature") == 1  # the feature query within five turns
    spent = np.cumsum([DEFAULT_COSTS[kind] for kind in kinds])
    rules = ExpertRules.load()
    for turn, total in enumerate(spent, start=1):  # paced; only the feature query may run ahead of the share
        assert total <= paced_budget(15, 30, turn, rules.head_start_turns) + DEFAULT_COSTS["feature"] + 1e-9
    for scene in range(3):  # every scene change gets part of the budget
        assert any(kind != "none" for kind in kinds[scene * 10:(scene + 1) * 10])
    demos = [a.concept for a in summary.actions if isinstance(a, DemoQuery)]
    assert len(set(demos)) == len(demos)  # one demonstration per concept, no more
    assert kinds.count("label") > kinds.count("demo") + kinds.count("feature")  # mostly the cheap query
    assert summary.accuracy > 0.5
    again = run_episode(make_strategy("scripted-expert"), TASK, np.random.default_rng(seed), **TRAINING)
    assert again.actions == summary.actions and again.explanations == summary.explanations


def test_the_feature_query_turn_is_drawn_from_the_strategy_generator():
    turns = set()
    for seed in range(12):
        summary = run_episode(ScriptedExpertStrategy(), TASK, np.random.default_rng(seed), **TRAINING)
        turns.add(next(t for t, a in enumerate(summary.actions, start=1) if a == FeatureQuery()))
    assert turns <= set(range(1, 6)) and len(turns) >= 3


def scene_state(spent=0.0, turn=0, budget=15.0, turns=30):
    rng = np.random.default_rng(5)
    state = LearningState(TASK.concepts, TASK.feature_names, budget, turns, change_every=10)
    X, _ = TASK.sample(12, rng)
    state.observe_scene(0, X)
    state.place_progress(turn=turn, spent=spent, history=["none"] * turn, feature_query_asked=True)
    return state


def test_a_demonstration_of_an_unseen_concept_first_then_the_pace_holds_it_back():
    state = scene_state()
    decision = make_strategy("scripted-expert").choose(state, np.random.default_rng(0))
    assert isinstance(decision.action, DemoQuery) and "no example of" in decision.explanation
    at_its_share = scene_state(spent=paced_budget(15, 30, 6, 3.0), turn=5)  # turn 6's share is spent
    decision = make_strategy("scripted-expert").choose(at_its_share, np.random.default_rng(0))
    assert decision.action == NoQuery() and "spread my budget" in decision.explanation


def test_the_plan_sees_only_the_learner_state_and_its_candidates():
    """Same state and candidates, same generator: the same choice, whatever else exists (no scene truth)."""
    state = scene_state()
    candidates = expected_decision_features(state)
    choices = {ExpertPlan().choose(1, state, candidates, np.random.default_rng(4)) for _ in range(3)}
    assert len(choices) == 1
    action, reason = choices.pop()
    assert action in candidates.actions and reason.endswith(".")


def test_rules_come_from_the_file_and_a_path_is_accepted(tmp_path):
    rules = ExpertRules.load(RULES_FILE)
    assert 1 <= rules.feature_query_by_turn <= 5 and 0 < rules.uncertain_margin <= 1
    custom = tmp_path / "rules.toml"
    custom.write_text("[feature_query]\nby_turn = 1\n[pace]\nhead_start_turns = 30\n[examples]\n"
                      "uncertain_margin = 1.0\n")
    strategy = make_strategy("scripted-expert", rules=custom)
    assert strategy.plan.rules == ExpertRules(1, 30.0, 1.0)
    summary = run_episode(strategy, TASK, np.random.default_rng(0), **TRAINING)
    assert summary.actions[0] == FeatureQuery()  # by_turn = 1: the very first turn
    custom.write_text("[feature_query]\nby_turn = 0\n[pace]\nhead_start_turns = 3\n[examples]\n"
                      "uncertain_margin = 0.5\n")
    with pytest.raises(ValueError, match=r"\[feature_query\].*by_turn"):
        make_strategy("scripted-expert", rules=custom)
