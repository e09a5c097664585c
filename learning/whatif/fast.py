"""The fast what-if engine: one-site Laplace updates, shared demo/label states, batched refits (thesis eq. 6.3).

* Instance answers. Adding <x, y> makes x a positive for y's classifier and a
  negative for every other one, so each classifier only ever sees two
  what-ifs per scene object: "x is mine" and "x is not mine". For every
  classifier the joint posterior over the scene is computed once, then every
  (object, sign) pair is a rank-one update plus one correction step
  (``laplace.one_site_probabilities``): |Y| x |X| x 2 updates instead of
  (|Y| |X| + |X| |Y|) x |Y| refits. One table serves both the demo queries and
  the label queries.
* The feature-subset query. Answer y switches every classifier to F_{y,c}.
  Every distinct subset is refit exactly for every classifier that does not
  already use it: through a low-rank kernel (pivoted Cholesky, Newton in the
  weight space) when the subset has up to three features, else in one batched
  Newton over all remaining (subset, classifier) pairs, warm-started from the
  current latent modes. Subsets are cached per training set, the outcomes per
  model version and scene.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from learning.gp import default_length_scale, rbf_kernel
from learning.whatif.base import Outcomes, WhatIfEngine, cached, feature_query_subsets
from learning.whatif.laplace import (
    fit_modes,
    fit_weight_space,
    one_site_probabilities,
    pad_columns,
    pivoted_cholesky,
    predict_from_modes,
    predict_weight_space,
    scene_kernels,
    scene_posterior,
    stack_posteriors,
)

# The feature-query refits use a low-rank kernel when the answer has few features: an RBF kernel on up to
# three standardised features has low numerical rank (pivoted Cholesky to 1e-4 of the variance needs ~9
# columns for one feature, ~35 for two, ~100 for three at n = 500; the probabilities move by < 1e-4), and
# then a Newton step costs O(n r^2) instead of O(n^3). Beyond n / 3 columns the dense path is cheaper.
LOW_RANK_MAX_FEATURES = 3
LOW_RANK_TOLERANCE = 1e-4
LOW_RANK_MAX_FRACTION = 3
# Low-rank subsets are fitted in batches of similar rank, each padded to its band's largest: the C build
# and solve grow with the padded rank squared and cubed, a batch's Python overhead is paid once. Two bands
# (1-feature subsets, ~10 columns; 2-feature, ~35) cost 17 % less than one at n 150, 25 % at n 500.
RANK_BANDS = (16, 48)
# From this many examples the dense refits start Newton at the mode of a rank-40 approximation of the
# subset's kernel (``_dense_starts``) instead of the classifier's current mode: about 2 float32 Cholesky
# factorisations per refit instead of 5 (-40 % of _fit_dense at n 500). Below, factorisations are cheap and
# the start costs more than it saves (+4 % at n 150).
DENSE_WARM_FROM = 300
DENSE_START_RANK = 40
THREE_FEATURES_FROM = 300  # three features need ~100 columns: cheaper than dense only from about n = 300


class FastEngine(WhatIfEngine):
    name = "fast"
    outcomes_by_version = True  # its outcomes are a function of the model version and the scene (cached so)

    def simulate(self, state, label_objects: Sequence[int], feature_query: bool) -> Outcomes:
        pairs = cached(state, "fast.pairs", (state.version, state.scene_id), lambda: pair_table(state))
        label_objects = tuple(int(i) for i in label_objects)
        demo = pairs.transpose(1, 0, 2, 3)  # [y, x] views of the one [x, y] table
        label = pairs[list(label_objects)]
        feature = None
        if feature_query:
            feature = cached(state, "fast.feature", (state.version, state.scene_id), lambda: feature_outcomes(state))
        return Outcomes(demo, label, feature, label_objects, shared=True)


def pair_table(state, extra: np.ndarray | None = None) -> np.ndarray:
    """[x, y, i, c]: p(c | scene object i) after adding <scene object x, concept y> to the training set.

    Classifiers on the same features share their kernels (they share the training rows) and their one-site
    updates run as one batch (``one_site_probabilities`` on ``stack_posteriors``). ``extra`` (raw rows, as the
    scene's) joins the scene on both axes: x and i then run over the scene objects, then the extra rows
    (``learning.decision.voi`` scores a pool of objects seen before this way).
    """
    scene = state.scaled_scene() if extra is None else state.scaler.transform(np.vstack([state.scene_X, extra]))
    n_objects, n_concepts = len(scene), len(state.concepts)
    table = np.empty((n_objects, n_concepts, n_objects, n_concepts))
    groups: dict[tuple, list[int]] = {}
    for c, concept in enumerate(state.concepts):
        model = state.concept_model(concept)
        groups.setdefault((tuple(state.model_columns(concept)), model.length_scale_), []).append(c)
    for (columns, length_scale), members in groups.items():
        first = state.concept_model(state.concepts[members[0]])
        kernels = scene_kernels(first.X_train_, scene[:, columns], length_scale, first.variance)
        posteriors = [scene_posterior(state.concept_model(state.concepts[c]), scene[:, columns], kernels)
                      for c in members]
        signed = one_site_probabilities(stack_posteriors(posteriors))  # [g, +1 / -1, x, i]
        for g, c in enumerate(members):
            table[:, :, :, c] = signed[g, 1][:, None, :]
            table[:, c, :, c] = signed[g, 0]
    return table


def feature_outcomes(state, extra: np.ndarray | None = None) -> np.ndarray:
    """[y, i, c]: p(c | scene object i) if the teacher answered the FSQ with F_{y,c} (thesis §6.4.2).

    Each distinct subset is refit once per classifier: with a low-rank kernel when the subset has one
    (``_fit_low_rank``), else exactly, every remaining (subset, classifier) pair one row of a single
    batched ``fit_modes`` call warm-started from the classifier's current latent mode. ``extra`` (raw rows)
    joins the scene as in ``pair_table``: i runs over the scene objects, then the extra rows.
    """
    subsets = cached(state, "fast.subsets", state.training_version, lambda: feature_query_subsets(state))
    X, labels = state.scaled_training()
    if extra is None:
        scene, current = state.scaled_scene(), state.probabilities()
    else:
        judged = np.vstack([state.scene_X, extra])
        scene, current = state.scaler.transform(judged), state.probabilities(judged)
    concepts = state.concepts
    outcome = np.empty((len(concepts), len(scene), len(concepts)))
    if len(X) == 0:  # no data: every subset gives the prior
        outcome[:] = current[None]
        return outcome
    distinct: dict[tuple[int, ...], np.ndarray] = {}
    for answer in concepts:
        distinct.setdefault(tuple(int(i) for i in subsets[answer]), np.empty((len(scene), len(concepts))))
    rows = []  # (subset, classifier) pairs to refit
    for key, probabilities in distinct.items():
        subset = np.array(key)
        for c, concept in enumerate(concepts):
            columns = state.model_columns(concept)
            if len(columns) == len(subset) and np.array_equal(columns, subset):
                probabilities[:, c] = current[:, c]  # the answer changes nothing for this classifier
            else:
                rows.append((key, c))
    low_rank, dense_rows = {}, []
    for key in dict.fromkeys(key for key, _ in rows):
        Phi = _low_rank_features(state, np.array(key), X, scene)
        if Phi is None:
            dense_rows += [(k, c) for k, c in rows if k == key]
        else:
            low_rank[key] = Phi
    if low_rank:
        _fit_low_rank(state, [(k, c) for k, c in rows if k in low_rank], low_rank, len(X), labels, distinct)
    if dense_rows:
        _fit_dense(state, dense_rows, X, labels, scene, distinct)
    for y, answer in enumerate(concepts):
        outcome[y] = distinct[tuple(int(i) for i in subsets[answer])]
    return outcome


def _length_scale(state, subset: np.ndarray) -> float:
    return state.length_scale or default_length_scale(len(subset))


def _low_rank_features(state, subset, X, scene) -> np.ndarray | None:
    """Phi with K ~ Phi Phi^T over the training rows then the scene rows, if the subset's kernel allows."""
    if len(subset) > LOW_RANK_MAX_FEATURES or (len(subset) == LOW_RANK_MAX_FEATURES and len(X) < THREE_FEATURES_FROM):
        return None
    variance = state.kernel_variance
    points = np.vstack([X[:, subset], scene[:, subset]])
    return pivoted_cholesky(points, _length_scale(state, subset), variance, LOW_RANK_TOLERANCE * variance,
                            len(X) // LOW_RANK_MAX_FRACTION)


def _fit_low_rank(state, rows, features, n_train, labels, distinct) -> None:
    """Refit every (subset, classifier) row in weight space.

    Subsets whose rank falls in one of ``RANK_BANDS`` share one batched Newton (padded to one width: the
    Python overhead of a small fit is its cost); a larger-rank subset gets its own (padding would cost more).
    """
    groups: list[list] = []
    for low, high in zip((0,) + RANK_BANDS[:-1], RANK_BANDS):
        band = [key for key, Phi in features.items() if low < Phi.shape[1] <= high]
        groups += [band] if band else []
    groups += [[key] for key, Phi in features.items() if Phi.shape[1] > RANK_BANDS[-1]]
    for keys in groups:
        members = [(key, c) for key, c in rows if key in keys]
        targets = np.array([np.where(labels == state.concepts[c], 1.0, -1.0) for _, c in members])
        if len(keys) == 1:
            Phi = features[keys[0]]
            train, scene = Phi[:n_train], Phi[n_train:]
        else:
            Phi = pad_columns([features[key] for key in keys])[[keys.index(key) for key, _ in members]]
            train, scene = Phi[:, :n_train], Phi[:, n_train:]
        z, C = fit_weight_space(train, targets)
        fitted = predict_weight_space(scene, state.kernel_variance, z, C)
        for (key, c), probabilities in zip(members, fitted):
            distinct[key][:, c] = probabilities


def _fit_dense(state, rows, X, labels, scene, distinct) -> None:
    """Refit every (subset, classifier) row exactly, all in one batched Newton (``fit_modes``)."""
    concepts, variance = state.concepts, state.kernel_variance
    keys = list(dict.fromkeys(key for key, _ in rows))
    kernels, cross = [], []
    for key in keys:
        subset = np.array(key)
        kernels.append(rbf_kernel(X[:, subset], X[:, subset], _length_scale(state, subset), variance))
        cross.append(rbf_kernel(X[:, subset], scene[:, subset], _length_scale(state, subset), variance))
    kernel_of_row = np.array([keys.index(key) for key, _ in rows])
    targets = np.array([np.where(labels == concepts[c], 1.0, -1.0) for _, c in rows])
    if len(X) >= DENSE_WARM_FROM:
        start = _dense_starts(state, rows, X, targets)
    else:
        start = np.array([state.concept_model(concepts[c]).f_hat_ for _, c in rows])  # current latent modes
    sw, factors, gradient = fit_modes(np.stack(kernels), targets, kernel_of_row, start)
    fitted = predict_from_modes(np.stack(cross), variance, sw, factors, gradient, kernel_of_row)
    for (key, c), probabilities in zip(rows, fitted):
        distinct[key][:, c] = probabilities


def _dense_starts(state, rows, X, targets) -> np.ndarray:
    """Starting latent values for the dense refits: the modes under K ~ Phi Phi^T, Phi the first
    ``DENSE_START_RANK`` pivoted-Cholesky columns of each subset's kernel (weight-space Newton, O(n r^2)).

    Only the start: Psi is concave, so ``fit_modes`` still converges to the exact mode, in fewer full steps.
    """
    start = np.empty_like(targets)
    for key in dict.fromkeys(key for key, _ in rows):
        subset = np.array(key)
        Phi = pivoted_cholesky(X[:, subset], _length_scale(state, subset), state.kernel_variance,
                               LOW_RANK_TOLERANCE * state.kernel_variance, DENSE_START_RANK, truncate=True)
        assert Phi is not None, "a truncated pivoted Cholesky always returns its columns"
        members = [b for b, (k, _) in enumerate(rows) if k == key]
        z, _ = fit_weight_space(Phi, targets[members])
        start[members] = z @ Phi.T
    return start
