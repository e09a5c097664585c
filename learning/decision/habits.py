"""Decision features for the expert's habits that the thesis's seven cannot express (issue 27; docs/irl.md).

U(s) = w . phi(s) is linear (eq. 7.2) and scored at each candidate's next state s' (eq. 7.1). Under
eq. 7.1 the levels of budget spent and of remaining time are the same in every candidate's row of a
turn, so no weight on the seven features can say "slow down, most of the budget is gone" or "ask the
feature query early". Each feature here is a function of s' in [0, 1] that serves one rule of the
scripted expert (learning/strategies/scripted_expert.py, the thesis's §7.4.1 expert); they were chosen
from those rules and the training condition alone, before any evaluation:

* ``pace_overrun``              rule 2, pacing: spent'/B - (elapsed'/T + PACE_LEAD), clipped to [0, 1].
* ``feature_query_overdue``     rule 1, the feature query early: min(1, turn' / 5) while it is unasked.
* ``concepts_without_example``  rule 3, an example of every concept: the fraction with no positive example.
* ``unsure_unlabelled``         rule 4, label what the robot is unsure of: the fraction of scene objects
                                not yet labelled whose label margin p(y1|x) - p(y2|x) is below 0.5.

The constants are the expert's own (its TOML and §7.4.1): a head start of 3 of the training condition's
30 turns, five turns for the feature query, the margin 0.5.
"""

from __future__ import annotations

import numpy as np

from learning.decision.features import FEATURE_NAMES

HABIT_FEATURES: tuple[str, ...] = (
    "pace_overrun",
    "feature_query_overdue",
    "concepts_without_example",
    "unsure_unlabelled",
)
EXTENDED_FEATURE_NAMES: tuple[str, ...] = FEATURE_NAMES + HABIT_FEATURES  # the seven, then the habits
PACE_LEAD = 0.1  # the expert's head start h / T = 3 / 30 turns in the training condition
FEATURE_QUERY_TURNS = 5  # "within the first five turns" (thesis §7.4.1)
UNSURE_MARGIN = 0.5  # the expert's uncertain_margin


def pace_overrun(spent: float, budget: float, turn: int, turns: int) -> float:
    """How far the budget spent runs ahead of the time elapsed plus the expert's lead, at the end of ``turn``."""
    if budget <= 0 or turns <= 0:
        return 0.0
    return float(np.clip(spent / budget - (turn / turns + PACE_LEAD), 0.0, 1.0))


def feature_query_overdue(feature_query_asked: bool, turn: int) -> float:
    """0 once the feature query is asked; before, the turns gone by out of the expert's five, at most 1."""
    return 0.0 if feature_query_asked else min(1.0, turn / FEATURE_QUERY_TURNS)


def concepts_without_example(counts: np.ndarray) -> np.ndarray:
    """The fraction of concepts with no positive example, for class counts (..., |Y|)."""
    return (np.asarray(counts) <= 0).mean(axis=-1)


def unsure_objects(P: np.ndarray) -> np.ndarray:
    """(..., |X|) True where an object's label margin (p(y|x) normalised over the concepts) is below 0.5."""
    P = np.asarray(P, dtype=float)
    total = P.sum(axis=-1, keepdims=True)
    Q = np.where(total > 0, P / np.where(total > 0, total, 1.0), 1.0 / P.shape[-1])
    if Q.shape[-1] < 2:
        return np.zeros(Q.shape[:-1], dtype=bool)
    top_two = np.sort(Q, axis=-1)[..., -2:]
    return top_two[..., 1] - top_two[..., 0] < UNSURE_MARGIN


def unsure_unlabelled(unsure: np.ndarray, labelled: np.ndarray) -> np.ndarray:
    """The fraction of scene objects unsure and not labelled; ``labelled`` (..., |X|) broadcasts with ``unsure``."""
    n_objects = unsure.shape[-1]
    if n_objects == 0:
        return np.zeros(unsure.shape[:-1])
    return (unsure & ~labelled).sum(axis=-1) / n_objects


def expected_habits(state, actions, outcomes, P: np.ndarray, counts: np.ndarray, demo_weights: dict,
                    label_weights: dict) -> np.ndarray:
    """E[habit features of s' | a] for every action (rows in ``actions`` order, columns HABIT_FEATURES).

    ``outcomes`` are the what-if engine's next-state probabilities (``learning.whatif.Outcomes``, or None when
    nothing is simulated); ``demo_weights[concept]`` is p(x|y) over the scene and ``label_weights[object]``
    p(y|x) over the concepts, the answer distributions of ``learning.decision.candidates``.
    """
    n_objects, n_concepts = P.shape
    labelled_now = np.zeros(n_objects, dtype=bool)
    labelled_now[list(state.labelled_in_scene)] = True
    turn_after = state.turn + 1
    with_one_more = counts + np.eye(n_concepts)
    missing_after_example = concepts_without_example(with_one_more)  # (|Y|,): after one example of concept y
    unsure_quiet = unsure_unlabelled(unsure_objects(P), labelled_now)
    concept_index = {c: k for k, c in enumerate(state.concepts)}
    rows = np.empty((len(actions), len(HABIT_FEATURES)))
    demo_unsure = np.zeros((n_concepts, n_objects))  # replaced whenever a query was simulated
    if outcomes is not None and n_objects:
        shown = labelled_now[None, :] | np.eye(n_objects, dtype=bool)  # row x: the shown object x labelled too
        demo_unsure = unsure_unlabelled(unsure_objects(outcomes.demo), shown[None, :, :])  # (|Y|, |X|)
    for i, action in enumerate(actions):
        spent = state.spent + state.cost(action)
        fsq_done = state.feature_query_asked or action.kind == "feature"
        rows[i, 0] = pace_overrun(spent, state.budget, turn_after, state.turns)
        rows[i, 1] = feature_query_overdue(fsq_done, turn_after)
        if action.kind == "demo":
            y = concept_index[action.concept]
            rows[i, 2] = missing_after_example[y]
            rows[i, 3] = demo_weights[action.concept] @ demo_unsure[y]
        elif action.kind == "label":
            x = action.object_index
            rows[i, 2] = label_weights[x] @ missing_after_example
            if outcomes.shared:
                rows[i, 3] = label_weights[x] @ demo_unsure[:, x]
            else:
                k = outcomes.label_objects.index(x)
                mask = labelled_now.copy()
                mask[x] = True
                rows[i, 3] = label_weights[x] @ unsure_unlabelled(unsure_objects(outcomes.label[k]), mask)
        elif action.kind == "feature":
            rows[i, 2] = concepts_without_example(counts)
            rows[i, 3] = unsure_unlabelled(unsure_objects(outcomes.feature), labelled_now).mean()
        else:
            rows[i, 2] = concepts_without_example(counts)
            rows[i, 3] = unsure_quiet
    return rows
