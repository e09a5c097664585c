"""The brute-force what-if oracle: refit every classifier for every (query, answer) pair (thesis eq. 6.3).

Plain on purpose: each demonstration answer and each label answer is
simulated on its own (the same <x, y> state is refit once for the demo query
and once for the label query), every classifier is refit from scratch with
the same ``ConceptModels`` code the learner uses, and nothing is cached. The
tests and ``scripts/bench_decision.py`` compare the fast engine against it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from learning.concepts import ConceptModels
from learning.whatif.base import Outcomes, WhatIfEngine, feature_query_subsets


class ReferenceEngine(WhatIfEngine):
    name = "reference"

    def simulate(self, state, label_objects: Sequence[int], feature_query: bool) -> Outcomes:
        X, labels = state.scaled_training()
        scene = state.scaled_scene()
        concepts = state.concepts

        def refit(extra_row: np.ndarray | None, extra_label: str | None, subsets) -> np.ndarray:
            rows, names = X, labels
            if extra_row is not None:
                rows = np.vstack([X, extra_row[None, :]])
                names = np.append(labels, np.array([extra_label], dtype=object))
            models = ConceptModels(concepts, variance=state.kernel_variance, length_scale=state.length_scale)
            return models.fit(rows, names, subsets).predict(scene)

        current = state.feature_subsets
        demo = np.array([[refit(scene[x], concept, current) for x in range(len(scene))] for concept in concepts])
        label = np.array([[refit(scene[x], concept, current) for concept in concepts] for x in label_objects])
        feature = None
        if feature_query:
            subsets = feature_query_subsets(state)
            feature = np.array([refit(None, None, {c: subsets[answer] for c in concepts}) for answer in concepts])
        demo = demo.reshape(len(concepts), len(scene), len(scene), len(concepts))
        label = label.reshape(len(label_objects), len(concepts), len(scene), len(concepts))
        return Outcomes(demo, label, feature, tuple(int(i) for i in label_objects))
