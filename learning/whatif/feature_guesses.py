"""Guesses of the teacher's answer to the feature-subset query, as readings of thesis §6.4.2 (issue 49 item 3).

The thesis values an FSQ by "the computational feature subsets generated" (line 945): "∀y ∈ Y, it simulates a
resulting state s' by changing F_y to F_{y,c} ... with probability 1/|Y|". The text leaves open which
classifiers take which subset, and what a concept without positive and negative examples (no subset
generated) contributes. Each guess below is one reading; every one returns the answers it simulates as
(probability, {concept: feature indices}) and uses only the learner's own training set, never the teacher's.

* ``per-concept`` (what the engines do; ``learning.whatif.fast.feature_outcomes``): answer y switches every
  classifier to F_{y,c}, 1/|Y| each; a concept with no subset generated answers with every feature.
* ``generated-only``: the same answers, uniform over the concepts whose selector generated a subset.
* ``union``: one answer, the union of the generated subsets, for every classifier: the real question asks for
  one "subset of features useful for discriminating between the task-relevant classes" (line 869).
* ``own-subset``: one state, every classifier with its own F_{y,c} ("retrains all symbol classifiers ... with
  F_{y,c} as the underlying representation"); a concept with no subset keeps its features.

A state with no subset generated anywhere gets no answer from the last three (the FSQ then changes nothing).
"""

from __future__ import annotations

from collections.abc import Hashable

import numpy as np

from learning.concepts import ConceptModels
from learning.whatif.base import feature_query_subsets

Answer = tuple[float, dict[Hashable, np.ndarray | None]]
GUESSES = ("per-concept", "generated-only", "union", "own-subset")


def generated(state) -> dict[Hashable, bool]:
    """Whether the computational selector generated F_{y,c} for each concept: it has positive and negative examples."""
    _, labels = state.training_matrix()
    labels = list(labels)
    return {c: 0 < sum(label == c for label in labels) < len(labels) for c in state.concepts}


def guessed_answers(state, guess: str) -> list[Answer]:
    """The answers ``guess`` simulates for the FSQ in ``state``, each with its probability (module docstring)."""
    if guess not in GUESSES:
        raise ValueError(f"unknown feature-answer guess {guess!r}; accepted: {', '.join(GUESSES)}")
    concepts = state.concepts
    if len(state.training_matrix()[0]) == 0:
        return []
    subsets, made = feature_query_subsets(state), generated(state)
    if guess == "per-concept":
        return [(1.0 / len(concepts), {c: subsets[y] for c in concepts}) for y in concepts]
    sources = [y for y in concepts if made[y]]
    if not sources:
        return []
    if guess == "generated-only":
        return [(1.0 / len(sources), {c: subsets[y] for c in concepts}) for y in sources]
    if guess == "union":
        union = np.unique(np.concatenate([subsets[y] for y in sources]))
        return [(1.0, {c: union for c in concepts})]
    current = state.fitted_feature_subsets
    return [(1.0, {c: subsets[c] if made[c] else current[c] for c in concepts})]


def refit_probabilities(state, subsets, rows: np.ndarray, training: tuple | None = None, scaler=None) -> np.ndarray:
    """p(y|x) of raw ``rows`` after refitting every classifier from scratch with ``subsets`` (the learner's own
    ``ConceptModels``, as the reference what-if engine refits) on the training set, or on ``training`` = (raw X,
    labels) if given, scaled by ``scaler`` (default the state's); the state is not changed."""
    scaler = state.scaler if scaler is None else scaler
    X, labels = state.training_matrix() if training is None else training
    models = ConceptModels(state.concepts, variance=state.kernel_variance, length_scale=state.length_scale)
    return models.fit(scaler.transform(X), labels, subsets).predict(scaler.transform(rows))
