"""Computational feature selection for concept grounding (thesis chapter 5, §5.3).

Three selectors from the thesis, usable on any feature matrix ``X`` (n_samples x
n_features) and class labels ``y``:

* **FI**, the information-gain filter (eq. 5.1): keep each feature whose gain
  about the class is above zero once the gain expected by chance is removed.
* **ES**, greedy forward selection on the CFS merit (eq. 5.2).
* **ER**, greedy backward elimination on the same merit.

Choices the thesis leaves open (it used Weka), made here and used throughout:

* Discretisation: equal-frequency bins, ``default_bin_count`` = ceil(n ** (1/3))
  clipped to [2, 10] (3 bins at n = 12, 5 at n = 100). A feature with no more
  distinct values than bins (a hand open/closed flag) keeps its own values;
  equal values always share a bin; a constant feature is one bin, gain 0.
* Entropies are plug-in estimates in bits.
* Chance: the G statistic 2 n ln(2) I(Y; f) with Williams' small-sample
  correction is compared with chi-square at ``significance`` (default 0.05).
* CFS correlations are symmetrical uncertainties SU = 2 I / (H_a + H_b) on the
  discretised features (Hall's choice) with Miller-Madow bias-corrected
  entropies. A feature whose class association fails the chance test gets
  r_cf = 0, as Hall's MDL discretisation leaves such a feature one interval;
  so ES and ER pick among the features FI keeps, and prune their redundancy.
* Deterministic: no randomness; ties go to the lower feature index.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable

import numpy as np

from learning.features.information import (
    COPY_TOLERANCE,
    DEFAULT_SIGNIFICANCE,
    DiscreteFeatures,
    LazyCorrelations,
    as_feature_matrix,
    check_count,
    check_significance,
    default_bin_count,
    discretize,
    prepare,
)

SELECTION_METHODS = ("none", "FI", "ES", "ER")
__all__ = ["SELECTION_METHODS", "backward_elimination", "cfs_merit", "chance_corrected_information_gain",
           "computational_subsets", "default_bin_count", "discretize", "filter_information_gain",
           "forward_selection", "information_gain", "merit_from_correlations", "select_features",
           "symmetrical_uncertainty"]
_RELATIVE_TOLERANCE = 1e-12

def _resolve_method(method) -> str:
    for name in SELECTION_METHODS:
        if isinstance(method, str) and method.strip().lower() == name.lower():
            return name
    accepted = ", ".join(repr(name) for name in SELECTION_METHODS)
    raise ValueError(f"unknown feature selection method {method!r}; accepted: {accepted} (any case)")


def information_gain(X, y, *, n_bins: int | None = None) -> np.ndarray:
    """Plug-in I(Y|f) = H(Y) - H(Y | f) in bits per feature (eq. 5.1); 0 if f or y is constant."""
    table, class_codes = prepare(X, y, n_bins)
    return table.gains(class_codes)


def chance_corrected_information_gain(
    X, y, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None
) -> np.ndarray:
    """I(Y|f) minus the gain independence exceeds with probability ``significance``.

    Plug-in gain is biased upwards: with n = 12 nearly every noise feature has
    I > 0. Under independence the G statistic 2 n ln(2) I (I in bits) divided by
    Williams' factor q >= 1 is close to chi-square with (K_f - 1)(K_y - 1)
    degrees of freedom, so I - q chi2_{1-significance} / (2 n ln 2) is > 0
    exactly when that G-test rejects independence. Constant features get 0.
    """
    significance = check_significance(significance)
    table, class_codes = prepare(X, y, n_bins)
    return table.chance_corrected_gains(class_codes, significance)


def filter_information_gain(
    X, y, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None
) -> np.ndarray:
    """FI (§5.3.1): sorted indices of features with I(Y|f) > 0 after chance correction.

    The thesis keeps I(Y|f) > tau, tau = 0; on plug-in estimates that keeps
    nearly every feature of a small sample, so "> 0" is applied to
    ``chance_corrected_information_gain``. The result may be empty
    (``select_features`` then returns all features).
    """
    return np.flatnonzero(chance_corrected_information_gain(X, y, significance=significance, n_bins=n_bins) > 0.0)


def symmetrical_uncertainty(
    X, y, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The CFS correlations: feature-class r_cf (F,) and feature-feature r_ff (F, F)."""
    significance = check_significance(significance)
    table, class_codes = prepare(X, y, n_bins)
    return table.class_su(class_codes, significance), table.feature_su


def _merit(sum_class, sum_pairs, size):
    # m mean(r_cf) = sum over features; m (m - 1) mean(r_ff) = 2 * sum over pairs.
    return sum_class / np.sqrt(size + 2.0 * sum_pairs)


def merit_from_correlations(class_correlations, feature_correlations) -> float:
    """CFS merit (eq. 5.2) M = m r_cf / sqrt(m + m (m - 1) r_ff) of a subset of m features.

    The thesis prints m(m + 1); Hall's CFS (1999), which it cites, has m(m - 1), used
    here. r_cf: mean of ``class_correlations`` (m,); r_ff: mean off-diagonal entry of
    the symmetric ``feature_correlations`` (m, m).
    """
    class_correlations = np.asarray(class_correlations, dtype=float)
    feature_correlations = np.asarray(feature_correlations, dtype=float)
    size = class_correlations.size
    if class_correlations.ndim != 1 or size == 0 or feature_correlations.shape != (size, size):
        raise ValueError(
            "need class correlations of shape (m,), m >= 1, and feature correlations of shape (m, m); "
            f"got {class_correlations.shape} and {feature_correlations.shape}"
        )
    pairs = (feature_correlations.sum() - np.trace(feature_correlations)) / 2.0
    return float(_merit(class_correlations.sum(), pairs, size))


def cfs_merit(X, y, subset, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None) -> float:
    """CFS merit (eq. 5.2, m(m - 1) as in Hall) of ``subset`` with the module's SU correlations."""
    significance = check_significance(significance)
    features = as_feature_matrix(X)
    indices = np.asarray(subset)
    if indices.ndim != 1 or indices.size == 0 or indices.dtype.kind not in "iu":
        raise ValueError(f"subset must be a non-empty 1-D sequence of integer feature indices; got {subset!r}")
    if np.any(indices < 0) or np.any(indices >= features.shape[1]) or np.unique(indices).size != indices.size:
        raise ValueError(f"subset must hold distinct indices in [0, {features.shape[1] - 1}]; got {indices.tolist()}")
    table, class_codes = prepare(features[:, indices], y, n_bins)
    return merit_from_correlations(table.class_su(class_codes, significance), table.feature_su)


def _tolerance(merit: float) -> float:
    return _RELATIVE_TOLERANCE * max(1.0, abs(merit))


def _representatives(feature_su: np.ndarray) -> np.ndarray:
    """Mask of features that copy no lower-indexed feature (SU = 1: same partition).

    Doubling every feature of a subset leaves its merit unchanged, a plateau
    greedy elimination cannot cross, so the search sees one member per copy group.
    """
    copies_earlier = np.triu(feature_su >= 1.0 - COPY_TOLERANCE, k=1)
    return ~np.asarray(copies_earlier.any(axis=0))


def _forward(class_su: np.ndarray, feature_su, max_features: int | None) -> np.ndarray:
    """Greedy CFS forward search; ``feature_su`` is the SU matrix or ``LazyCorrelations`` (rows on demand)."""
    n_features = class_su.size
    if not np.any(class_su > 0):
        return np.arange(n_features)
    # Only features with r_cf > 0 can raise the merit (a zero adds nothing above the line and grows the
    # denominator), and an exact copy has the same r_cf as its original: look for copies among those.
    relevant = np.flatnonzero(class_su > 0)
    if isinstance(feature_su, LazyCorrelations):
        # Copies have the same SU with the class (up to rounding): look for them only if two values meet.
        may_copy = np.any(np.diff(np.sort(class_su[relevant])) < COPY_TOLERANCE)
        distinct = feature_su.representatives(relevant) if may_copy else np.ones(len(relevant), dtype=bool)
    else:
        distinct = _representatives(feature_su[np.ix_(relevant, relevant)])
    eligible, chosen = np.zeros(n_features, dtype=bool), np.zeros(n_features, dtype=bool)
    eligible[relevant[distinct]] = True
    links = np.zeros(n_features)  # SU summed between each feature and the chosen ones
    sum_class, pairs, merit, size = 0.0, 0.0, 0.0, 0
    while size < (max_features or n_features):
        candidates = _merit(sum_class + class_su, pairs + links, size + 1)
        candidates[chosen | ~eligible] = -np.inf
        best = int(np.argmax(candidates))  # ties: lowest index
        if candidates[best] <= merit + _tolerance(merit):
            break
        chosen[best] = True
        sum_class, pairs = sum_class + class_su[best], pairs + links[best]
        links += feature_su[best]
        merit, size = float(candidates[best]), size + 1
    return np.flatnonzero(chosen)


def _backward(class_su: np.ndarray, feature_su: np.ndarray) -> np.ndarray:
    n_features = class_su.size
    if not np.any(class_su > 0):
        return np.arange(n_features)
    kept = _representatives(feature_su)
    off_diagonal = feature_su - np.diag(np.diag(feature_su))
    links = off_diagonal[:, kept].sum(axis=1)  # SU summed with the other kept features
    sum_class, size = class_su[kept].sum(), int(kept.sum())
    pairs = off_diagonal[np.ix_(kept, kept)].sum() / 2.0
    merit = float(_merit(sum_class, pairs, size))
    while size > 1:
        without = _merit(sum_class - class_su, np.maximum(pairs - links, 0.0), size - 1)
        without[~kept] = -np.inf
        worst = n_features - 1 - int(np.argmax(without[::-1]))  # ties: drop the highest index
        if without[worst] < merit - _tolerance(merit):
            break
        kept[worst] = False
        sum_class, pairs = sum_class - class_su[worst], pairs - links[worst]
        links -= off_diagonal[worst]
        merit, size = float(without[worst]), size - 1
    return np.flatnonzero(kept)


def forward_selection(
    X, y, max_features: int | None = None, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None
) -> np.ndarray:
    """ES (§5.3.1): greedy forward search on the CFS merit (eq. 5.2); sorted indices.

    Adds the feature that raises the merit most until none does (or ``max_features``).
    If no feature passes the chance test (one class, too few samples) there is
    nothing to select on and all features are returned.
    """
    check_count(max_features, "max_features", 1)
    significance = check_significance(significance)
    table, class_codes = prepare(X, y, n_bins)
    return _forward(table.class_su(class_codes, significance), LazyCorrelations(table), max_features)


def backward_elimination(X, y, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None) -> np.ndarray:
    """ER (§5.3.1): greedy backward elimination on the CFS merit (eq. 5.2); sorted indices.

    From all features (one per group of exact copies), removes the one whose removal
    raises the merit most while it does not fall (ties favour the smaller subset);
    at least one stays. If no feature passes the chance test, all are returned.
    """
    significance = check_significance(significance)
    table, class_codes = prepare(X, y, n_bins)
    return _backward(table.class_su(class_codes, significance), table.feature_su)


def _select(table: DiscreteFeatures, class_codes: np.ndarray, method: str, significance: float) -> np.ndarray:
    if method == "FI":
        chosen = np.flatnonzero(table.chance_corrected_gains(class_codes, significance) > 0.0)
        if chosen.size:
            return chosen
    if method == "ES":
        return _forward(table.class_su(class_codes, significance), LazyCorrelations(table), None)
    if method == "ER":
        return _backward(table.class_su(class_codes, significance), table.feature_su)
    return np.arange(table.n_features)


def select_features(
    X, y, method: str, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None
) -> np.ndarray:
    """Sorted indices chosen by ``method``, one of SELECTION_METHODS (any case); never empty.

    "none": all features; "FI": ``filter_information_gain``, or all features if
    none passes; "ES": ``forward_selection``; "ER": ``backward_elimination``.
    """
    name = _resolve_method(method)
    significance = check_significance(significance)
    table, class_codes = prepare(X, y, n_bins)
    return _select(table, class_codes, name, significance)


def computational_subsets(
    X,
    labels,
    concepts: Iterable[Hashable],
    method: str = "ES",
    *,
    significance: float = DEFAULT_SIGNIFICANCE,
    n_bins: int | None = None,
) -> dict[Hashable, np.ndarray]:
    """F_{y,c} (§6.4.2): concept -> the subset ``method`` selects for ``labels == concept``.

    One-vs-rest per concept; labels may be strings or integers. A concept with
    no positive or no negative example yet gets all features. Discretisation and
    feature-feature correlations are computed once for all concepts.
    """
    name = _resolve_method(method)
    significance = check_significance(significance)
    features = as_feature_matrix(X)
    label_list = labels.tolist() if isinstance(labels, np.ndarray) else list(labels)
    if len(label_list) != features.shape[0]:
        raise ValueError(f"labels has {len(label_list)} entries but X has {features.shape[0]} rows; they must match")
    table = DiscreteFeatures(features, n_bins)
    subsets: dict[Hashable, np.ndarray] = {}
    for concept in concepts:
        is_concept = np.array([label == concept for label in label_list], dtype=np.intp)
        if 0 < is_concept.sum() < is_concept.size:
            subsets[concept] = _select(table, is_concept, name, significance)
        else:
            subsets[concept] = np.arange(features.shape[1])
    return subsets
