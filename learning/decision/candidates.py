"""Expected decision features of every candidate action: the input to DT and to IRL (thesis eq. 6.3, 7.1, 7.2).

For a learning state s and each affordable candidate a, ``expected_decision_features``
returns E[phi(s') | a] = sum_{s'} P(s' | a) phi(s'), so that with the linear
utility U(s) = w . phi(s) the expected utility is EU(a) = w . E[phi(s') | a].

* DemoQuery(y): the teacher shows scene object x with p(x|y) = p(y|x) / sum_x' p(y|x')
  (the per-concept classifier's probabilities, normalised over the scene).
* LabelQuery(x): the teacher names concept y with p(y|x) normalised over the concepts.
* FeatureQuery: every classifier switches to F_{y,c} with probability 1/|Y| each.
* Every action, no query included, is scored at its own next state s_{t+1} (eq. 7.1): the clock
  advances one turn whatever is done. A query's next state has spent + cost and t_NQ = 0; NoQuery's
  has spent (+ its cost, 0 by default), t_NQ = min(q + 1, W) / W for a quiet run q now and window W,
  and the learning features of the current classifiers (nothing is learned by staying quiet).
  "argmax over all rows" is eq. 7.1's rule, "take a* only if EU(a*) > EU(no query)"; ties go to no
  query. (The thesis's chapter-6 rule compares with U(s) instead: the same only when every environment
  feature weighs 0; docs/strategies.md.) ``current`` keeps phi(s) itself, which no longer equals any row.

Candidates, in this fixed order: a DemoQuery per concept (state.concepts
order; not for a concept the teacher could not show in this scene), a
LabelQuery per scene object not yet labelled in this scene (index order), the
FeatureQuery until it has been asked, NoQuery last. Only queries the remaining
budget covers are candidates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from learning.actions import Action, DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.decision.embodied import absent_chance
from learning.decision.features import (
    FEATURE_NAMES,
    concept_counts,
    label_distribution,
    learning_features,
    state_clock,
)
from learning.decision.habits import EXTENDED_FEATURE_NAMES, expected_habits
from learning.whatif import WhatIfEngine, make_engine
from learning.whatif.base import cached


@dataclass(frozen=True)
class CandidateFeatures:
    """One turn's candidates and E[phi(s') | a] for each (rows in ``actions`` order, columns FEATURE_NAMES)."""

    actions: tuple[Action, ...]
    expected: np.ndarray  # (len(actions), len(FEATURE_NAMES))
    current: np.ndarray  # phi(s) now, (len(FEATURE_NAMES),); not the NoQuery row, which is at s_{t+1}
    feature_names: tuple[str, ...] = FEATURE_NAMES
    seconds: np.ndarray | None = None  # embodied costs: E[seconds(a)] of every candidate (None: time in turns)

    def utilities(self, weights) -> np.ndarray:
        """EU(a) = w . E[phi(s') | a] for every candidate (eq. 7.1, 7.2)."""
        return self.expected @ np.asarray(weights, dtype=float)

    @property
    def no_query_index(self) -> int:
        return len(self.actions) - 1

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(action.kind for action in self.actions)


def candidate_actions(state) -> tuple[Action, ...]:
    """The affordable candidates of this turn in the fixed order (module docstring); NoQuery is always last.

    A state with a ``cache`` keeps the tuple while its inputs (the scene and what was said about it, the
    feature question, what the budget affords per kind) stay the same: the same objects, so that the
    decision cache of ``_expected_seven`` recognises them by identity."""
    kinds = {"demo": DemoQuery(state.concepts[0]), "label": LabelQuery(0), "feature": FeatureQuery()}
    affordable = {kind: state.can_afford(action) for kind, action in kinds.items()}  # a cost is its kind's
    cache = getattr(state, "cache", None)
    if cache is None:
        return _candidate_actions(state, affordable)
    key = (state.scene_id, len(state.scene_X), state.labelled_in_scene, state.absent_in_scene,
           state.feature_query_asked, tuple(affordable.values()))
    return cached(state, "candidates.actions", key, lambda: _candidate_actions(state, affordable))


def _candidate_actions(state, affordable: dict[str, bool]) -> tuple[Action, ...]:
    n_objects = len(state.scene_X)
    labelled = state.labelled_in_scene
    # A demonstration is drawn from the scene: none without objects, nor for a concept the teacher
    # already could not find in this scene.
    queries: list[Action] = [DemoQuery(c) for c in state.concepts if n_objects and c not in state.absent_in_scene]
    queries += [LabelQuery(i) for i in range(n_objects) if i not in labelled]
    if not state.feature_query_asked:
        queries.append(FeatureQuery())
    return tuple(a for a in queries if affordable[a.kind]) + (NoQuery(),)


def expected_decision_features(state, engine: str | WhatIfEngine = "fast", window_factor: float = 1.0,
                               actions: tuple[Action, ...] | None = None, seconds: bool = True,
                               habits: bool = False) -> CandidateFeatures:
    """E[phi(s') | a] for every candidate action of ``state`` (thesis eq. 6.3, 7.1) with the given what-if engine.

    ``actions`` defaults to ``candidate_actions(state)``; a caller may pass a subset (NoQuery included or not).
    With embodied costs (``state.seconds_clock``; ``seconds`` False ignores them) every row's remaining time is
    read at its own next state in seconds, (T_s - elapsed - E[seconds(a)]) / T_s (thesis §8.2.2), and
    ``seconds`` of the result holds E[seconds(a)]. ``habits`` appends the expert-habit features of
    ``learning.decision.habits`` (columns EXTENDED_FEATURE_NAMES; ``current`` keeps the seven).
    """
    table = _expected_seven(state, engine, window_factor, actions, seconds, need_outcomes=habits)
    if not habits:
        return table.candidates
    P, counts = table.probabilities, table.counts
    demo_weights = {c: _normalised(P[:, y]) for y, c in enumerate(state.concepts)}
    label_weights = dict(enumerate(label_distribution(P))) if len(P) else {}
    extra = expected_habits(state, table.candidates.actions, table.outcomes, P, counts, demo_weights, label_weights)
    seven = table.candidates
    return CandidateFeatures(seven.actions, np.hstack([seven.expected, extra]), seven.current,
                             EXTENDED_FEATURE_NAMES, seven.seconds)


@dataclass(frozen=True)
class _SevenFeatureTable:
    candidates: CandidateFeatures
    probabilities: np.ndarray
    counts: np.ndarray
    outcomes: object  # learning.whatif.Outcomes, or None when no query needed simulating


def _expected_seven(state, engine, window_factor, actions, seconds, need_outcomes=False) -> _SevenFeatureTable:
    """The candidates with E[phi(s') | a] over the thesis's seven features (eq. 6.3, 7.1).

    The learning-feature columns of every row, and phi(s)'s own, are a function of the model version, the
    scene and the candidates when the engine's outcomes are (``outcomes_by_version``, the fast engine's): a
    turn with none of them changed (a quiet one) takes them from the state's cache, the same bits; only the
    environment columns are computed anew. ``need_outcomes``: simulate anyway (the table carries them).
    """
    engine = make_engine(engine)
    actions = candidate_actions(state) if actions is None else tuple(actions)
    clock = state_clock(state, window_factor, seconds)
    counts = concept_counts(state)
    P = state.probabilities()
    durations = _expected_seconds(clock, actions, P, state.concepts)
    version = (engine.name, state.version, state.scene_id, actions) \
        if getattr(engine, "outcomes_by_version", False) else None
    entry = state.cache.get("candidates.learned") if version is not None else None
    if entry is not None and entry[0] == version and not need_outcomes:
        (now, learned), outcomes = entry[1], None
    else:
        now, learned, outcomes = _learned_columns(state, engine, actions, P, counts)
        if version is not None:
            for kept in (now, learned):
                if kept is not None:
                    kept.setflags(write=False)
            state.cache["candidates.learned"] = (version, (now, learned))
    environment = clock.features()
    current = np.concatenate([now, environment])
    quiet = np.concatenate([now, clock.after(state.cost(NoQuery()), asked=False,
                                             seconds=_quiet_seconds(clock)).features()])
    if learned is None:  # no query to simulate: every row is no query's next state
        return _SevenFeatureTable(CandidateFeatures(actions, np.tile(quiet, (len(actions), 1)), current,
                                                    seconds=durations), P, counts, None)
    expected = np.empty((len(actions), len(current)))
    expected[:, : len(now)] = learned
    after = {}  # the next turn's environment features, per query cost
    for i, action in enumerate(actions):
        if action.kind == "none":
            expected[i] = quiet
            continue
        key = (state.cost(action), 0.0 if durations is None else float(durations[i]))
        if key not in after:
            after[key] = clock.after(key[0], asked=True, seconds=key[1]).features()
        expected[i, len(now) :] = after[key]
    return _SevenFeatureTable(CandidateFeatures(actions, expected, current, seconds=durations), P, counts, outcomes)


def _learned_columns(state, engine, actions, P, counts):
    """phi(s)'s learning features, E[learning features of s' | a] per row (no query's rows left unset; None
    when there is no query to simulate) and the engine's outcomes (eq. 6.3)."""
    now = learning_features(P, counts)
    label_objects = [a.object_index for a in actions if a.kind == "label"]
    wants_feature_query = any(a.kind == "feature" for a in actions)
    if not (label_objects or wants_feature_query or any(a.kind == "demo" for a in actions)):
        return now, None, None
    outcomes = engine.simulate(state, label_objects, wants_feature_query)
    n_concepts = len(state.concepts)
    with_one_more = counts + np.eye(n_concepts)  # row y: the counts after one more example of concept y
    # Learning features of every simulated next state, all at once: (|Y|, |X|, 4), (k, |Y|, 4), (|Y|, 4).
    # Shared outcomes (the fast engine's) are a function of the model version and the scene, and so are the
    # counts: a turn with neither changed reuses the features scored before, the same bits.
    reuse = (state.version, state.scene_id) if outcomes.shared else None
    demo_phi = _scored(state, "demo", reuse, lambda: learning_features(outcomes.demo, with_one_more[:, None, :]))
    if outcomes.shared:  # the same <x, y> states: score them once
        label_phi = demo_phi[:, list(outcomes.label_objects)].transpose(1, 0, 2)
    else:
        label_phi = learning_features(outcomes.label, with_one_more[None, :, :])
    feature_phi = None if outcomes.feature is None else _scored(
        state, "feature", reuse, lambda: learning_features(outcomes.feature, counts))
    label_rows = {index: k for k, index in enumerate(outcomes.label_objects)}
    concept_index = {c: k for k, c in enumerate(state.concepts)}
    learned = np.empty((len(actions), demo_phi.shape[-1]))
    positions = {kind: [i for i, a in enumerate(actions) if a.kind == kind] for kind in ("demo", "label", "feature")}
    if positions["demo"]:  # the teacher's object x with p(x|y), the classifier's column normalised over the scene
        ys = [concept_index[a.concept] for a in actions if isinstance(a, DemoQuery)]
        weights = np.array([_normalised(P[:, y]) for y in ys])
        learned[positions["demo"]] = np.einsum("dx,dxk->dk", weights, demo_phi[ys])
    if positions["label"]:  # the teacher's concept y with p(y|x) normalised over the concepts
        objects = [a.object_index for a in actions if isinstance(a, LabelQuery)]
        rows = [label_rows[x] for x in objects]
        learned[positions["label"]] = np.einsum("ly,lyk->lk", label_distribution(P)[objects], label_phi[rows])
    if positions["feature"]:  # each F_{y,c} with probability 1/|Y|
        assert feature_phi is not None, "the engine simulates the feature query whenever one is a candidate"
        learned[positions["feature"]] = feature_phi.mean(axis=0)
    return now, learned, outcomes


def _scored(state, part: str, version, compute):
    """``compute()``, kept in the state's cache for ``version`` (None: computed every time, nothing kept)."""
    if version is None:
        return compute()

    def kept():
        value = compute()
        value.setflags(write=False)
        return value

    return cached(state, f"candidates.{part}_phi", version, kept)


def _expected_seconds(clock, actions, P: np.ndarray, concepts) -> np.ndarray | None:
    """E[seconds(a)] of every action with embodied costs, else None."""
    if clock.seconds is None:
        return None
    absent = dict(zip(concepts, absent_chance(P)))
    return np.array([clock.seconds.expected_seconds(a, absent.get(getattr(a, "concept", None), 0.0))
                     for a in actions])


def _quiet_seconds(clock) -> float:
    return 0.0 if clock.seconds is None else clock.seconds.expected_seconds(NoQuery())


def _normalised(column: np.ndarray) -> np.ndarray:
    total = column.sum()
    return column / total if total > 0 else np.full(len(column), 1.0 / max(len(column), 1))
