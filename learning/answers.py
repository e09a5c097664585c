"""Teachers' answers in the learner's terms: checking them, and what applying one did.

``LearningState.apply(action, answer)`` is the one place an answer changes the
learner; it checks the answer with :func:`check_answer` before anything changes,
records the turn and returns a :class:`Change`, which ``LearningState.undo``
takes back. ``apply_answer(state, action, answer)`` is the same call as a function.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from learning.actions import Action
from learning.concepts import checked_row, checked_subset
from learning.errors import TeachbotError
from learning.examples import Example


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
    example: Example | None = field(default=None, compare=False, repr=False)  # the row an "example" added
    cost: float = field(default=0.0, compare=False)  # the budget the answer's turn was charged (refunded by undo)


@dataclass(frozen=True)
class DemoRow:
    """A demonstration given as a row of feature values rather than a scene index (an object from elsewhere,
    such as one fetched from the pantry)."""

    x: object


class QuestionContext(Protocol):
    """What checking an answer reads of the learner (``LearningState`` is one): the concepts, the feature
    names and the current scene's rows."""

    @property
    def concepts(self) -> tuple[str, ...]: ...

    @property
    def feature_names(self) -> tuple[str, ...]: ...

    @property
    def scene_X(self) -> np.ndarray: ...


class Learner(Protocol):
    """A learner an answer can be applied to (``LearningState`` is one)."""

    def apply(self, action: Action, answer) -> Change: ...


def check_answer(state: QuestionContext, action: Action, answer):
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
    if action.kind == "demo" and isinstance(answer, DemoRow):
        try:
            return DemoRow(checked_row(answer.x, len(state.feature_names), f"the demonstration of '{action.concept}'"))
        except ValueError as error:
            raise AnswerError(str(error)) from None
    if kind == "demo":
        n = len(state.scene_X)
        if isinstance(answer, (bool, np.bool_)) or not isinstance(answer, (int, np.integer)) or not 0 <= answer < n:
            raise AnswerError(f"the answer to a demonstration query is the index of an object of the current scene "
                              f"(0..{n - 1}), a DemoRow, or None if there is none, got {answer!r}")
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


def apply_answer(state: Learner, action: Action, answer) -> Change:
    """``state.apply(action, answer)``: learn from the answer and record the turn (see LearningState.apply)."""
    return state.apply(action, answer)
