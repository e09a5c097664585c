"""learning.check_strategy: every shipped strategy keeps the contract, and a strategy broken in each rule is caught."""

import itertools

import pytest

from learning import (
    STRATEGY_NAMES,
    Decision,
    DemoQuery,
    FeatureQuery,
    LabelQuery,
    NoQuery,
    Strategy,
    StrategyCheckError,
    check_strategy,
    make_strategy,
)
from learning.errors import SettingsError
from learning.strategies.check import RULES

SHIPPED = (*STRATEGY_NAMES, "learning.strategies.examples:EveryOtherTurn",
           "rl:learning/rl/policies/questioner-ch7-training.toml")


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_strategy_passes(name):
    report = check_strategy(make_strategy(name), seeds=(0, 1))
    assert report.rules == RULES and report.states == 12 and report.seeds == (0, 1)
    assert str(report).startswith(f"{name}: passed {len(RULES)} checks on 12 synthetic states (seeds 0, 1)")


class Quiet(Strategy):
    """Keeps every rule: the base of the broken ones below."""

    def choose(self, state, rng):
        return Decision(NoQuery(), "I stay quiet.")


class NoDecision(Quiet):
    def choose(self, state, rng):
        return NoQuery(), "a tuple, not a Decision"


class NoExplanation(Quiet):
    def choose(self, state, rng):
        return Decision(NoQuery(), "  ")


class Raises(Quiet):
    def choose(self, state, rng):
        raise KeyError("oops")


class OutsideTheScene(Quiet):
    def choose(self, state, rng):
        return Decision(LabelQuery(99) if len(state.scene_X) else NoQuery(), "Object 100, please.")


class UnknownConcept(Quiet):
    def choose(self, state, rng):
        return Decision(DemoQuery("tulip") if state.can_afford(DemoQuery("tulip")) else NoQuery(), "Show a tulip.")


class Mutates(Quiet):
    def choose(self, state, rng):
        state.apply(NoQuery())  # the loop's job, not the strategy's
        return super().choose(state, rng)


COUNTER = itertools.count()  # module-level: a copy of the strategy shares it


class Undetermined(Quiet):
    def choose(self, state, rng):
        return Decision(LabelQuery(next(COUNTER) % 2) if len(state.scene_X) > 1 and state.can_afford(LabelQuery(0))
                        else NoQuery(), "Whichever.")


class IgnoresTheBudget(Quiet):
    def choose(self, state, rng):
        return Decision(LabelQuery(0) if len(state.scene_X) else NoQuery(), "What is object 1?")


class IgnoresAnEmptyScene(Quiet):
    def choose(self, state, rng):
        return Decision(LabelQuery(0) if state.can_afford(LabelQuery(0)) else NoQuery(), "What is object 1?")


class AsksFeaturesAgain(Quiet):
    def choose(self, state, rng):
        return Decision(FeatureQuery() if state.can_afford(FeatureQuery()) else NoQuery(), "Which features?")


@pytest.mark.parametrize("broken, rule, words", [
    (NoDecision, RULES[0], "returned (NoQuery(kind='none'), 'a tuple, not a Decision'); return learning.Decision"),
    (NoExplanation, RULES[0], "gave the explanation '  '"),
    (Raises, RULES[0], "raised KeyError: 'oops'"),
    (OutsideTheScene, RULES[1], "asked LabelQuery(object_index=99, kind='label'), which the state refuses"),
    (UnknownConcept, RULES[1], "DemoQuery(concept='tulip', kind='demo'), which the state refuses"),
    (Mutates, RULES[2], "changed the state"),
    (Undetermined, RULES[3], "with an rng of the same seed"),
    (IgnoresTheBudget, RULES[4], "on a state whose budget is spent, seed 0 it asked LabelQuery"),
    (IgnoresAnEmptyScene, RULES[5], "on a state with an empty scene (no objects), seed 0"),
    (AsksFeaturesAgain, RULES[6], "on a state whose feature query was answered, seed 0 it asked the feature query"),
])
def test_a_strategy_broken_in_one_rule_is_caught_with_a_readable_message(broken, rule, words):
    with pytest.raises(StrategyCheckError) as caught:
        check_strategy(broken())
    message = str(caught.value)
    assert message.startswith(f"{broken.__name__} {rule}: on ") and words in message and "\n" not in message
    assert isinstance(caught.value, SettingsError)  # the command line prints it as one line


def test_the_rules_broken_above_are_all_the_rules():
    assert check_strategy(Quiet()).rules == RULES


def test_an_object_without_choose_is_refused():
    with pytest.raises(StrategyCheckError, match="has no choose\\(state, rng\\) method"):
        check_strategy(object())
