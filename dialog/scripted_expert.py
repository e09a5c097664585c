"""A scripted expert questioner, modelled on the expert of thesis §7.4.1, for demonstrations and tests.

The thesis's expert (one of its authors) "always requested relevant features
(FSQ) early in the learning episode (within the first five turns), focused
most queries on the least costly query type, and focused on quickly acquiring
representative training examples for each class", spreading the budget over
the scene changes. ``ScriptedExpertChooser`` follows these rules, in order,
each turn (numbers from dialog/data/scripted-expert.toml):

1. Feature query: at a turn f drawn once per episode, uniformly from 1..5
   (or the first turn after f it can afford), ask FSQ.
2. Pace: spread the budget over the allocated time (and so over the scene
   changes): by turn t of T at most B (t + h) / T may be spent, h a head start
   of 3 turns so that a scene's first turns can ask; a query that would go
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
choice uses the strategy's generator from the episode seed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dialog.expert import ExpertView
from learning.actions import Action, DemoQuery, FeatureQuery, NoQuery
from learning.datafiles import check_keys, integer, number, read_toml, section
from learning.decision.features import label_distribution

RULES_FILE = Path(__file__).parent / "data" / "scripted-expert.toml"


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
        check_keys(data, where, required=("feature_query", "pace", "examples"))
        tables = {key: section(data, key, where) for key in ("feature_query", "pace", "examples")}
        for key, field_name in (("feature_query", "by_turn"), ("pace", "head_start_turns"),
                                ("examples", "uncertain_margin")):
            check_keys(tables[key], f"{where} [{key}]", required=(field_name,))
        rules = cls(integer(tables["feature_query"], "by_turn", f"{where} [feature_query]", low=1),
                    number(tables["pace"], "head_start_turns", f"{where} [pace]", low=0.0),
                    number(tables["examples"], "uncertain_margin", f"{where} [examples]", low=0.0, high=1.0))
        return rules


def paced_budget(budget: float, turns: int, turn: int, head_start: float) -> float:
    """The most the expert may have spent by the end of ``turn`` (1-based): B min(1, (t + h) / T)."""
    return budget * min(1.0, (turn + head_start) / turns)


class ScriptedExpertChooser:
    """The rules of the module docstring; one instance per episode (it plans its feature-query turn once)."""

    name = "scripted-expert"

    def __init__(self, rules: ExpertRules | None = None):
        self.rules = rules or ExpertRules.load()
        self.feature_turn: int | None = None

    def choose(self, view: ExpertView) -> Action:
        state, candidates, rng = view.state, set(view.candidates.actions), view.rng
        if self.feature_turn is None:
            self.feature_turn = int(rng.integers(1, self.rules.feature_query_by_turn + 1))
        if FeatureQuery() in candidates and view.turn >= self.feature_turn:
            return FeatureQuery()
        allowance = paced_budget(state.budget, state.turns, view.turn, self.rules.head_start_turns) - state.spent + 1e-9
        for wanted in self._wanted(view, candidates, rng):
            if state.cost(wanted) <= allowance:
                return wanted
        return NoQuery()

    def _wanted(self, view: ExpertView, candidates: set, rng: np.random.Generator) -> list[Action]:
        """Rules 3 and 4: the queries the expert would like to ask now, most wanted first (pace aside)."""
        state, wishes = view.state, []
        counts = state.counts_per_concept()
        unseen = [c for c in state.concepts if counts[c] == 0 and DemoQuery(c) in candidates]
        if unseen:
            wishes.append(DemoQuery(unseen[int(rng.integers(len(unseen)))]))
        Q = label_distribution(state.probabilities())
        names = view.candidates.feature_names
        evens, sharpens = names.index("class_distribution_uniformity"), names.index("classifier_discriminability")
        unsure = []
        for row, action in enumerate(view.candidates.actions):
            if action.kind == "label":
                top_two = np.sort(Q[action.object_index])[::-1][:2]
                if len(top_two) < 2 or top_two[0] - top_two[1] < self.rules.uncertain_margin:
                    expected = view.candidates.expected[row]
                    unsure.append((round(float(expected[evens]), 9), round(float(expected[sharpens]), 9), action))
        if unsure:
            wishes.append(max(unsure, key=lambda entry: entry[:2])[2])
        return wishes
