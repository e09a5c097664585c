"""A scripted expert questioner, modelled on the expert of thesis §7.4.1: the strategy ``scripted-expert``.

The thesis's expert (one of its authors) "always requested relevant features
(FSQ) early in the learning episode (within the first five turns), focused
most queries on the least costly query type, and focused on quickly acquiring
representative training examples for each class", spreading the budget over
the scene changes. ``ExpertPlan`` follows these rules, in order, each turn
(numbers from learning/strategies/data/scripted-expert.toml):

1. Feature query: at a turn f drawn once per episode, uniformly from 1..5
   (or the first turn after f it can afford), ask FSQ.
2. Pace: spread the budget over the allocated time (and so over the scene
   changes): by turn t of T at most B (t + h) / T may be spent, h a head start
   of a few turns so that a scene's first turns can ask; a query that would go
   past it waits (FSQ alone may use later turns' share).
3. A concept with no example yet (and not reported absent in this scene):
   ask for a demonstration of it, so that its first example is one the
   teacher finds representative. Several such concepts: the seeded rng picks.
4. Otherwise (or when the demonstration does not fit the pace), the cheap
   query: among the unlabelled objects the robot is unsure of (label margin
   p(y1|x) - p(y2|x) below ``uncertain_margin``), label the one whose answer
   is expected to even out the classes most (the largest expected class
   distribution uniformity in the candidates table, i.e. most likely an
   example of an under-represented concept), then to sharpen the classifiers
   most (expected discriminability); the first such object on a tie.
5. Otherwise stay quiet.

It reads only the learner's state and the turn's candidates (the robot's
perception and beliefs), never the hidden scene truth or the test set, so its
choices are ones the decision features can in principle explain. Every random
choice uses the strategy's generator. ``dialog.expert.scripted`` puts the same
plan behind ``teachbot expert --expert scripted``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from learning.actions import Action, Decision, DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.datafiles import check_keys, integer, number, read_toml, section
from learning.decision.candidates import CandidateFeatures
from learning.decision.features import label_distribution
from learning.state import LearningState
from learning.strategies.candidate_based import CandidateStrategy
from learning.whatif import make_engine

RULES_FILE = Path(__file__).parent / "data" / "scripted-expert.toml"
RULE_FIELDS = (("feature_query", "by_turn"), ("pace", "head_start_turns"), ("examples", "uncertain_margin"))


@dataclass(frozen=True)
class ExpertRules:
    """The numbers behind the rules (module docstring); read from scripted-expert.toml."""

    feature_query_by_turn: int = 5
    head_start_turns: float = 3.0
    uncertain_margin: float = 0.5

    @classmethod
    def load(cls, path: str | Path = RULES_FILE) -> ExpertRules:
        path = Path(path)
        data = read_toml(path, "scripted-expert rules")
        where = str(path)
        check_keys(data, where, required=tuple(key for key, _ in RULE_FIELDS))
        tables = {key: section(data, key, where) for key, _ in RULE_FIELDS}
        for key, field_name in RULE_FIELDS:
            check_keys(tables[key], f"{where} [{key}]", required=(field_name,))
        return cls(integer(tables["feature_query"], "by_turn", f"{where} [feature_query]", low=1),
                   number(tables["pace"], "head_start_turns", f"{where} [pace]", low=0.0),
                   number(tables["examples"], "uncertain_margin", f"{where} [examples]", low=0.0, high=1.0))


def paced_budget(budget: float, turns: int, turn: int, head_start: float) -> float:
    """The most the expert may have spent by the end of ``turn`` (1-based): B min(1, (t + h) / T)."""
    return budget * min(1.0, (turn + head_start) / turns)


class ExpertPlan:
    """The rules of the module docstring; one instance per episode (it draws its feature-query turn once)."""

    def __init__(self, rules: ExpertRules | None = None):
        self.rules = rules or ExpertRules.load()
        self.feature_turn: int | None = None

    def choose(self, turn: int, state: LearningState, candidates: CandidateFeatures,
               rng: np.random.Generator) -> tuple[Action, str]:
        """The action for 1-based ``turn`` (one of ``candidates.actions``) and the rule that chose it, in words."""
        offered = set(candidates.actions)
        if self.feature_turn is None:
            self.feature_turn = int(rng.integers(1, self.rules.feature_query_by_turn + 1))
        if FeatureQuery() in offered and turn >= self.feature_turn:
            return FeatureQuery(), "Early in the episode I ask which features matter."
        share = paced_budget(state.budget, state.turns, turn, self.rules.head_start_turns)
        allowance = share - state.spent + 1e-9
        wishes = self._wanted(state, candidates, offered, rng)
        for wanted, reason in wishes:
            if state.cost(wanted) <= allowance:
                return wanted, reason
        if wishes:
            return NoQuery(), (f"Nothing to ask yet: I spread my budget over the episode, and by turn {turn} of "
                               f"{state.turns} I keep to {share:g} of {state.budget:g} (spent {state.spent:g}).")
        return NoQuery(), "Nothing to ask: I have an example of every concept and I am sure of every object here."

    def _wanted(self, state: LearningState, candidates: CandidateFeatures, offered: set,
                rng: np.random.Generator) -> list[tuple[Action, str]]:
        """Rules 3 and 4: the queries the expert would like to ask now, most wanted first (pace aside)."""
        wishes: list[tuple[Action, str]] = []
        counts = state.counts_per_concept()
        unseen = [c for c in state.concepts if counts[c] == 0 and DemoQuery(c) in offered]
        if unseen:
            concept = unseen[int(rng.integers(len(unseen)))]
            wishes.append((DemoQuery(concept), f"I have no example of {concept} yet, so I ask to be shown one."))
        Q = label_distribution(state.probabilities())
        names = candidates.feature_names
        evens, sharpens = names.index("class_distribution_uniformity"), names.index("classifier_discriminability")
        unsure = []
        for row, action in enumerate(candidates.actions):
            if isinstance(action, LabelQuery):
                top_two = np.sort(Q[action.object_index])[::-1][:2]
                if len(top_two) < 2 or top_two[0] - top_two[1] < self.rules.uncertain_margin:
                    expected = candidates.expected[row]
                    unsure.append((round(float(expected[evens]), 9), round(float(expected[sharpens]), 9), action))
        if unsure:
            action = max(unsure, key=lambda entry: entry[:2])[2]
            wishes.append((action, f"I am unsure what object {action.object_index + 1} is, and its label should "
                                   "even out my examples most, so I ask."))
        return wishes


class ScriptedExpertStrategy(CandidateStrategy):
    """The scripted expert as a strategy: the candidates exactly as DT computes them, the choice by ``ExpertPlan``."""

    name = "scripted-expert"

    def __init__(self, rules: ExpertRules | str | Path | None = None, engine="fast", window_factor: float = 1.0):
        self.plan = ExpertPlan(rules if isinstance(rules, ExpertRules) or rules is None else ExpertRules.load(rules))
        self.engine = make_engine(engine)
        self.window_factor = window_factor
        self.last_candidates: CandidateFeatures | None = None  # what the last choice saw (for IRL recording)

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        candidates, nothing = self.candidates(state)
        if nothing is not None:
            return nothing
        action, reason = self.plan.choose(state.turn + 1, state, candidates, rng)
        return Decision(action, reason)
