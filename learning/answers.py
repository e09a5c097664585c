"""Applying a teacher's answer to the learning state: one place, checked before anything changes.

``apply_answer(state, action, answer)`` takes an answer in the state's own terms
(concept names, scene object indices, feature indices or names) and returns a
:class:`Change` saying what it did. Call it *before* ``state.record_turn(action)``:
the turn's bookkeeping reads what the answer added (a demonstration query that
added no example marks its concept as absent from the scene).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from learning.actions import Action
from learning.concepts import checked_subset
from learning.errors import TeachbotError
from learning.state import LearningState


class AnswerError(TeachbotError):
    """An answer that does not fit its question (unknown concept, object not in the scene, unknown feature)."""


@dataclass(frozen=True)
class Change:
    """What an answer did: ``kind`` is "example" (a labelled row was added), "features" (the feature subsets
    were set), "absent" (no demonstration could be given), "skipped" (no answer) or "none" (no question)."""

    kind: str
    concept: str | None = None
    object: int | None = None
    source: str | None = None
    features: tuple[int, ...] | None = None
    previous_subsets: dict | None = field(default=None, compare=False, repr=False)


def check_answer(state: LearningState, action: Action, answer):
    """The answer in canonical form (a concept name, an object index, a sorted index array or None); an
    AnswerError naming what is accepted otherwise. Changes nothing."""
    kind = action.kind
    if answer is None:
        return None
    if kind == "none":
        raise AnswerError(f"no question was asked this turn, so the only answer is None, got {answer!r}")
    if kind == "label":
        if not isinstance(answer, str) or answer not in state.concepts:
            raise AnswerError(f"the answer to a label query is one of the concepts {list(state.concepts)} "
                              f"(or None to skip), got {answer!r}")
        return answer
    if kind == "demo":
        n = len(state.scene_X)
        if isinstance(answer, (bool, np.bool_)) or not isinstance(answer, (int, np.integer)) or not 0 <= answer < n:
            raise AnswerError(f"the answer to a demonstration query is the index of an object of the current scene "
                              f"(0..{n - 1}), or None if there is none, got {answer!r}")
        return int(answer)
    if kind == "feature":
        return feature_indices(state.feature_names, answer)
    raise AnswerError(f"unknown action {action!r}")


def feature_indices(feature_names, answer) -> np.ndarray:
    """Feature indices and/or names as sorted unique indices; an AnswerError naming what is accepted otherwise."""
    values = list(answer) if isinstance(answer, (list, tuple, set, frozenset, np.ndarray, range)) else [answer]
    names = list(feature_names)
    indices = []
    for value in values:
        if isinstance(value, str):
            if value not in names:
                raise AnswerError(f"unknown feature {value!r}; the answer to a feature query is feature names "
                                  f"({', '.join(names[:6])}{', ...' if len(names) > 6 else ''}) or indices "
                                  f"0..{len(names) - 1}, or None to skip")
            indices.append(names.index(value))
        else:
            indices.append(value)
    try:
        return checked_subset(indices, len(names), "the answer to a feature query")
    except AnswerError:
        raise
    except ValueError as error:
        raise AnswerError(f"{error} (or feature names, or None to skip)") from None


def apply_answer(state: LearningState, action: Action, answer) -> Change:
    """Learn from ``answer`` to ``action`` (checked first; a bad answer raises AnswerError and changes nothing).

    label: a concept name, the object's row joins the training set; demo: a scene object index (None: the
    teacher has none to show); feature: feature indices or names; None for no answer (no query: always None).
    """
    answer = check_answer(state, action, answer)
    if action.kind == "none":
        return Change("none")
    if answer is None:
        return Change("absent" if action.kind == "demo" else "skipped",
                      concept=getattr(action, "concept", None))
    if action.kind == "label":
        state.add_example(state.scene_X[action.object_index], answer, "label")
        return Change("example", concept=answer, object=action.object_index, source="label")
    if action.kind == "demo":
        state.add_example(state.scene_X[answer], action.concept, "demo")
        return Change("example", concept=action.concept, object=answer, source="demo")
    previous = dict(state.feature_subsets)
    state.set_feature_subset(answer)
    return Change("features", features=tuple(int(i) for i in answer), previous_subsets=previous)
