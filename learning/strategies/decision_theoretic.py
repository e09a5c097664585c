"""Decision-theoretic arbitration DT (thesis §6.4.2 eq. 6.2-6.3, §7.3.1 eq. 7.1-7.2).

For every affordable candidate the what-if engine simulates every answer and
``learning.decision.candidates`` turns the simulated next states into E[phi(s') | a].
With weights w the expected utility is EU(a) = w . E[phi(s') | a]; every action, no query
included, is scored at its own next state (eq. 7.1: the clock moves on, staying quiet learns
nothing and lengthens the quiet run). The learner takes the best query a* only if it beats
EU(no query), else it asks nothing this turn; ties between queries go to the first in
candidate order (demos, labels, FSQ). Expected utilities closer than ``EU_RESOLUTION`` are
equal (``learning.decision.resolution``), so that rounding decides neither a tie nor staying
quiet. Every explanation says what no query was scored at.

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
            queries = utilities[:-1]
            top = best_query(queries)
            return Decision(candidates.actions[stay], _quiet_reason(state, candidates.actions[top], queries[top],
                                                                      utilities[stay]))
        action = candidates.actions[best]
        reason = _query_reason(state, action, utilities[best], utilities[stay])
        if candidates.seconds is not None:  # embodied costs: the gain per expected second chose it
            took = candidates.seconds[best]
            reason += (f" It should take about {took:.1f} s, {(utilities[best] - utilities[stay]) / took:.4f} "
                       "utility a second, the most of the questions worth asking.")
        return Decision(action, reason)


def quiet_basis(state: LearningState) -> str:
    """What EU(no query) is scored at (eq. 7.1), in words."""
    run = state.quiet_run() + 1
    return (f"both scored at the next turn; staying quiet learns nothing and makes {run} quiet "
            f"turn{'s' if run != 1 else ''} in a row")


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


def _describe(state: LearningState, action: Action) -> str:
    if action.kind == "label":
        return f"asking what object {action.object_index + 1} is"
    if action.kind == "demo":
        return f"asking for a demonstration of {action.concept}"
    return "asking which features matter"


def _query_reason(state: LearningState, action: Action, utility: float, quiet: float) -> str:
    numbers = f"expected utility {utility:.3f} against {quiet:.3f} if I stay quiet, {quiet_basis(state)}"
    if action.kind == "label":
        P = normalise_rows(state.probabilities())
        first, second = (state.concepts[i] for i in np.argsort(P[action.object_index])[::-1][:2])
        return f"I can't tell {first} from {second} for object {action.object_index + 1}, so I ask ({numbers})."
    if action.kind == "demo":
        count = state.counts_per_concept()[action.concept]
        return (f"A demonstration of {action.concept} should help most: I have {count} "
                f"example{'s' if count != 1 else ''} of it ({numbers}).")
    return f"Knowing which features matter should help most ({numbers})."


def _quiet_reason(state: LearningState, best: Action, utility: float, quiet: float) -> str:
    numbers = (f"{_describe(state, best)} is worth {utility:.3f} against {quiet:.3f} for staying quiet, "
               f"{quiet_basis(state)}")
    if state.last_query_scene_id is not None and state.last_query_scene_id == state.scene_id:
        return f"Nothing to ask: the scene hasn't changed since my last question ({numbers})."
    return f"Nothing to ask: no question is worth its cost now ({numbers})."
