"""Decision-theoretic arbitration DT (thesis §6.4.2 eq. 6.2-6.3, §7.3.1 eq. 7.1-7.2).

For every affordable candidate the what-if engine simulates every answer and
``learning.decision.candidates`` turns the simulated next states into E[phi(s') | a].
With weights w the expected utility is EU(a) = w . E[phi(s') | a]; every action, no query
included, is scored at its own next state (eq. 7.1: the clock moves on, staying quiet learns
nothing and lengthens the quiet run). The learner takes the best query a* only if it beats
EU(no query), else it asks nothing this turn; ties between queries go to the first in
candidate order (demos, labels, FSQ). Expected utilities closer than ``EU_RESOLUTION`` are
equal (``learning.decision.resolution``), so that rounding decides neither a tie nor staying
quiet. Every explanation says in words which weighted feature decided (``learning.decision.reasons``), and
the decision carries each feature's term of EU(a*) - EU(no query) (``Decision.terms``).

With embodied costs (thesis §8.2.2; the state's ``seconds_clock``) remaining time reads seconds at each
candidate's own next state, (T_s - elapsed - E[seconds(a)]) / T_s (eq. 7.1), and of the queries that beat
no query DT takes the one with the largest expected utility gain per expected second
(``learning.decision.embodied.choose_per_second``): a near object before an equally useful far one.
``embodied=False`` ignores the seconds (time in turns, the rule above) even when the episode has them.

Named presets read their weights from learning/decision/presets/<name>.toml:
``dt`` (custom: edit the file or pass ``weights=``), ``dt-iros`` (ACD, CDU),
``dt-task`` (+ IV, PM) and ``dt-task-env`` (+ budget, time, non-query time;
its file is where IRL's learned weights go).
"""

from __future__ import annotations

import numpy as np

from learning.actions import Action, Decision
from learning.concepts import normalise_rows
from learning.decision.candidates import CandidateFeatures
from learning.decision.embodied import choose_per_second
from learning.decision.reasons import utility_terms, why_ask, why_quiet
from learning.decision.resolution import EU_RESOLUTION, first_of_best
from learning.decision.weights import resolve_weights, weighs_habits
from learning.state import LearningState
from learning.strategies.candidate_based import CandidateStrategy
from learning.whatif import make_engine


class DecisionTheoreticStrategy(CandidateStrategy):
    """DT with any weight vector: a preset name, a TOML path, a {feature: weight} mapping or a full vector."""

    def __init__(self, weights="dt", name: str | None = None, engine="fast", window_factor: float = 1.0,
                 embodied: bool = True):
        self.weights = resolve_weights(weights)
        self.name = name or (weights if isinstance(weights, str) and not weights.endswith(".toml") else "dt")
        self.engine = make_engine(engine)
        self.window_factor = window_factor
        self.embodied = embodied  # with embodied costs: remaining time in seconds, gain per expected second
        self.last_candidates: CandidateFeatures | None = None  # what the last choice saw (for IRL recording)

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        candidates, nothing = self.candidates(state, seconds=self.embodied, habits=weighs_habits(self.weights))
        if nothing is not None:
            return nothing
        utilities = candidates.utilities(self.weights)
        best, stay = choose_index(utilities, candidates.seconds), candidates.no_query_index
        if best == stay:
            top = best_query(utilities[:-1])
            terms = utility_terms(candidates.expected, self.weights, top, stay, candidates.feature_names)
            return Decision(candidates.actions[stay], _quiet_reason(state, terms), terms)
        action = candidates.actions[best]
        terms = utility_terms(candidates.expected, self.weights, best, stay, candidates.feature_names)
        reason = _query_reason(state, action, terms)
        if candidates.seconds is not None:  # embodied costs: the gain per expected second chose it
            reason += (f" Of the questions worth asking, it should gain the most per second it takes "
                       f"(about {max(1, round(float(candidates.seconds[best])))} s).")
        return Decision(action, reason, terms)


def choose_index(utilities: np.ndarray, seconds: np.ndarray | None = None) -> int:
    """argmax over the candidates, no query (the last) unless a query beats it by more than rounding.

    Queries within ``EU_RESOLUTION`` of the best are a tie, which goes to the first in candidate order.
    With embodied costs (``seconds``: E[seconds(a)] of every candidate), the query with the largest gain over
    no query per expected second among those that beat it (thesis §8.2.2 on eq. 7.1;
    :func:`learning.decision.embodied.choose_per_second`)."""
    if seconds is not None:
        return choose_per_second(utilities, seconds, EU_RESOLUTION)
    queries, stay = utilities[:-1], utilities[-1]
    if len(queries) == 0 or queries.max() <= stay + EU_RESOLUTION * max(1.0, abs(stay)):
        return len(utilities) - 1
    return best_query(queries)


def best_query(queries: np.ndarray) -> int:
    """The first query whose expected utility is within ``EU_RESOLUTION`` of the best one's."""
    return first_of_best(queries, EU_RESOLUTION * max(1.0, abs(float(queries.max()))))


def _query_reason(state: LearningState, action: Action, terms) -> str:
    """Why this question, in words: what it is about and the feature that decided it (no utility numbers)."""
    if action.kind == "label":
        P = normalise_rows(state.probabilities())
        first, second = (state.concepts[i] for i in np.argsort(P[action.object_index])[::-1][:2])
        return (f"I can't tell {first} from {second} for object {action.object_index + 1}, so I ask: "
                f"{why_ask(terms, first, 'label')}.")
    if action.kind == "demo":
        count = state.counts_per_concept()[action.concept]
        return (f"I ask for a demonstration of {action.concept}, of which I have {count} "
                f"example{'s' if count != 1 else ''}: {why_ask(terms, action.concept, 'demonstration')}.")
    return f"I ask which features matter: {why_ask(terms, 'the concepts', 'question')}."


def _quiet_reason(state: LearningState, terms) -> str:
    """Why no question, in words: what outweighed what the best question promised (no utility numbers)."""
    if state.last_query_scene_id is not None and state.last_query_scene_id == state.scene_id:
        return f"Nothing to ask: the scene hasn't changed since my last question, and {why_quiet(terms)}."
    return f"Nothing to ask: {why_quiet(terms)}."
