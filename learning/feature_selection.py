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

import math
from collections.abc import Hashable, Iterable
from functools import lru_cache

import numpy as np
from scipy.stats import chi2

SELECTION_METHODS = ("none", "FI", "ES", "ER")
DEFAULT_SIGNIFICANCE = 0.05
MAX_DEFAULT_BINS = 10
_RELATIVE_TOLERANCE = 1e-12
_COPY_TOLERANCE = 1e-9


@lru_cache(maxsize=4096)
def _chi2_quantile(probability: float, degrees: int) -> float:
    return float(chi2.ppf(probability, degrees))


def _chi2_quantiles(probability: float, degrees: np.ndarray) -> np.ndarray:
    """chi2.ppf for an array of (few distinct) degrees of freedom, each computed once."""
    distinct, inverse = np.unique(degrees, return_inverse=True)
    return np.array([_chi2_quantile(probability, int(d)) for d in distinct])[inverse.reshape(-1)]


def default_bin_count(n_samples: int) -> int:
    """Equal-frequency bins used for ``n_samples``: ceil(cbrt(n)) clipped to [2, 10]."""
    cube_root = round(max(n_samples, 1) ** (1.0 / 3.0), 9)
    return int(min(MAX_DEFAULT_BINS, max(2, math.ceil(cube_root))))


def _as_feature_matrix(X) -> np.ndarray:
    try:
        array = np.asarray(X)
    except (TypeError, ValueError) as error:
        raise ValueError("X must be a rectangular 2-D array of numbers (n_samples, n_features)") from error
    if array.dtype.kind not in "biuf":
        raise ValueError(f"X must hold numbers (float, int or bool); got dtype {array.dtype}")
    if array.ndim != 2:
        raise ValueError(f"X must be 2-D with shape (n_samples, n_features); got shape {array.shape}")
    if array.shape[0] < 1 or array.shape[1] < 1:
        raise ValueError(f"X needs at least one sample and one feature; got shape {array.shape}")
    array = array.astype(np.float64)
    if not np.all(np.isfinite(array)):
        raise ValueError("X contains NaN or infinite values; only finite numbers are accepted")
    return array


def _encode_labels(y, n_samples: int) -> np.ndarray:
    """Class labels (integers, booleans or strings) -> codes 0..K-1."""
    labels = np.asarray(y)
    if labels.ndim != 1:
        raise ValueError(f"y must be 1-D with one label per row of X; got shape {labels.shape}")
    if labels.shape[0] != n_samples:
        raise ValueError(f"y has {labels.shape[0]} labels but X has {n_samples} rows; they must match")
    kind = labels.dtype.kind
    if kind == "f" and not (np.all(np.isfinite(labels)) and np.all(labels == np.round(labels))):
        raise ValueError("y must hold class labels (integers, booleans or strings); got non-integer floats")
    if kind not in "fbiuUSO":
        raise ValueError(f"y must hold class labels (integers, booleans or strings); got dtype {labels.dtype}")
    try:
        _, codes = np.unique(labels, return_inverse=True)
    except TypeError as error:
        raise ValueError("y mixes label types that cannot be compared (e.g. ints and strings)") from error
    return codes.reshape(-1)


def _check_significance(significance: float) -> float:
    if isinstance(significance, bool) or not isinstance(significance, (int, float)) or not 0 < significance < 1:
        raise ValueError(f"significance must be a number strictly between 0 and 1; got {significance!r}")
    return float(significance)


def _check_count(value, name: str, minimum: int) -> None:
    if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum):
        raise ValueError(f"{name} must be None or an integer >= {minimum}; got {value!r}")


def _resolve_method(method) -> str:
    for name in SELECTION_METHODS:
        if isinstance(method, str) and method.strip().lower() == name.lower():
            return name
    accepted = ", ".join(repr(name) for name in SELECTION_METHODS)
    raise ValueError(f"unknown feature selection method {method!r}; accepted: {accepted} (any case)")


def _discretize(features: np.ndarray, n_bins: int) -> np.ndarray:
    """Equal-frequency codes for all columns at once (vectorised; see the module docstring)."""
    n_samples, n_features = features.shape
    order = np.argsort(features, axis=0, kind="stable")
    ordered = np.take_along_axis(features, order, axis=0)
    # A column with no more distinct values than bins keeps them: code = rank among its distinct values.
    new_value = np.vstack([np.zeros((1, n_features), dtype=np.intp), np.diff(ordered, axis=0) != 0])
    value_ranks = np.empty((n_samples, n_features), dtype=np.intp)
    np.put_along_axis(value_ranks, order, np.cumsum(new_value, axis=0), axis=0)
    few_values = value_ranks.max(axis=0, initial=0) + 1 <= n_bins
    if np.all(few_values):
        return value_ranks
    # Bin i starts at sorted position floor(i n / n_bins): sizes differ by at most one. Cuts halfway
    # between neighbours; a value's raw bin is the number of cuts at or below it.
    split_positions = (np.arange(1, n_bins) * n_samples) // n_bins
    below, above = ordered[split_positions - 1], ordered[split_positions]
    cuts = below + (above - below) / 2.0
    raw_bins = (features[:, None, :] >= cuts[None, :, :]).sum(axis=1)
    # Ties at a cut can merge or empty bins: renumber the occupied ones 0..K-1.
    occupied = np.zeros((n_bins, n_features), dtype=bool)
    occupied[raw_bins, np.arange(n_features)[None, :]] = True
    renumbered = np.take_along_axis(np.cumsum(occupied, axis=0) - 1, raw_bins, axis=0)
    return np.where(few_values[None, :], value_ranks, renumbered)


def discretize(X, n_bins: int | None = None) -> np.ndarray:
    """Equal-frequency bin codes 0..K_f-1 for every column of ``X`` (module docstring)."""
    _check_count(n_bins, "n_bins", 2)
    features = _as_feature_matrix(X)
    return _discretize(features, n_bins or default_bin_count(features.shape[0]))


def _joint_entropies(left: np.ndarray, right: np.ndarray, starts: np.ndarray):
    """Plug-in H(a, b) in bits and occupied cells, one-hot ``left`` vs each block of ``right``."""
    counts = left.T @ right
    probabilities = counts / left.shape[0]
    terms = -(probabilities * np.log2(np.where(probabilities > 0, probabilities, 1.0))).sum(axis=0)
    return np.add.reduceat(terms, starts), np.add.reduceat((counts > 0).sum(axis=0), starts)


def _symmetrical_uncertainty(mutual: np.ndarray, entropy_sums: np.ndarray) -> np.ndarray:
    """SU = 2 I / (H_a + H_b) clipped to [0, 1]; 0 when both variables are constant."""
    safe = np.where(entropy_sums > 0, entropy_sums, 1.0)
    return np.where(entropy_sums > 0, np.clip(2.0 * mutual / safe, 0.0, 1.0), 0.0)


class _DiscreteFeatures:
    """Discretised X plus what every selector reuses (entropies, bin sizes, SU matrix)."""

    def __init__(self, features: np.ndarray, n_bins: int | None):
        _check_count(n_bins, "n_bins", 2)
        self.n_samples, self.n_features = features.shape
        self.codes = _discretize(features, n_bins or default_bin_count(self.n_samples))
        self.levels = self.codes.max(axis=0) + 1
        self.starts = np.concatenate(([0], np.cumsum(self.levels)[:-1]))
        self.one_hot = np.zeros((self.n_samples, int(self.levels.sum())))
        self.one_hot[np.arange(self.n_samples)[:, None], self.starts + self.codes] = 1.0
        self.entropies = self._entropy(self.one_hot, self.starts)
        self.inverse_bin_sizes = np.add.reduceat(1.0 / self.one_hot.sum(axis=0), self.starts)
        self._feature_su: np.ndarray | None = None
        self._su_rows: dict[int, np.ndarray] = {}
        self._class_tables: dict[bytes, tuple] = {}

    def _entropy(self, one_hot: np.ndarray, starts: np.ndarray) -> np.ndarray:
        return _joint_entropies(np.ones((self.n_samples, 1)), one_hot, starts)[0]

    def _miller_madow(self, entropy, cells):
        """Plug-in entropy in bits plus its first-order bias (K - 1) / (2 n ln 2)."""
        return entropy + (cells - 1) / (2.0 * self.n_samples * math.log(2.0))

    def _against_class(self, class_codes: np.ndarray):
        """H(Y), its cell count, and H(Y, f) with occupied cells for every feature (kept per class vector)."""
        key = class_codes.tobytes()
        if key not in self._class_tables:
            class_one_hot = np.eye(int(class_codes.max()) + 1)[class_codes]
            joint, cells = _joint_entropies(class_one_hot, self.one_hot, self.starts)
            self._class_tables = {key: (self._entropy(class_one_hot, np.array([0]))[0], class_one_hot.shape[1],
                                        joint, cells)}
        return self._class_tables[key]

    def gains(self, class_codes: np.ndarray) -> np.ndarray:
        """Plug-in I(Y; f) = H(Y) + H(f) - H(Y, f) in bits for every feature (eq. 5.1)."""
        class_entropy, n_classes, joint, _ = self._against_class(class_codes)
        gains = np.clip(class_entropy + self.entropies - joint, 0.0, None)
        return np.where((self.levels > 1) & (n_classes > 1), gains, 0.0)

    def chance_corrected_gains(self, class_codes: np.ndarray, significance: float) -> np.ndarray:
        class_sizes = np.bincount(class_codes)
        degrees = (self.levels - 1) * (class_sizes.size - 1)
        safe_degrees = np.maximum(degrees, 1)
        n = self.n_samples
        williams = 1.0 + (n * self.inverse_bin_sizes - 1.0) * (n * np.sum(1.0 / class_sizes) - 1.0) / (
            6.0 * n * safe_degrees
        )
        critical = williams * _chi2_quantiles(1.0 - significance, safe_degrees) / (2.0 * n * math.log(2.0))
        return np.where(degrees > 0, self.gains(class_codes) - critical, 0.0)

    def class_su(self, class_codes: np.ndarray, significance: float) -> np.ndarray:
        """Bias-corrected feature-class SU; 0 for features that fail the chance test."""
        class_entropy, n_classes, joint, cells = self._against_class(class_codes)
        class_entropy = self._miller_madow(class_entropy, n_classes)
        marginals = self._miller_madow(self.entropies, self.levels)
        mutual = class_entropy + marginals - self._miller_madow(joint, cells)
        su = _symmetrical_uncertainty(mutual, class_entropy + marginals)
        return np.where(self.chance_corrected_gains(class_codes, significance) > 0.0, su, 0.0)

    @property
    def feature_su(self) -> np.ndarray:
        """Bias-corrected feature-feature SU matrix (diagonal 1, or 0 for a constant)."""
        if self._feature_su is None:
            marginals = self._miller_madow(self.entropies, self.levels)
            mutual = np.empty((self.n_features, self.n_features))
            bounds = np.append(self.starts, self.one_hot.shape[1])
            for feature in range(self.n_features):
                block = self.one_hot[:, bounds[feature] : bounds[feature + 1]]
                joint, cells = _joint_entropies(block, self.one_hot, self.starts)
                mutual[feature] = marginals[feature] + marginals - self._miller_madow(joint, cells)
            totals = marginals[:, None] + marginals[None, :]
            self._feature_su = _symmetrical_uncertainty((mutual + mutual.T) / 2.0, totals)
        return self._feature_su

    def feature_su_row(self, feature: int) -> np.ndarray:
        """One row of ``feature_su``, computed alone (forward selection needs only the chosen rows)."""
        if self._feature_su is not None:
            return self._feature_su[feature]
        if feature not in self._su_rows:
            marginals = self._miller_madow(self.entropies, self.levels)
            start = self.starts[feature]
            block = self.one_hot[:, start : start + self.levels[feature]]
            joint, cells = _joint_entropies(block, self.one_hot, self.starts)
            mutual = marginals[feature] + marginals - self._miller_madow(joint, cells)
            row = _symmetrical_uncertainty(mutual, marginals[feature] + marginals)
            row[feature] = 1.0 if marginals[feature] > 0 else 0.0
            self._su_rows[feature] = row
        return self._su_rows[feature]


class _LazyCorrelations:
    """Feature-feature SU rows on demand: what ES reads of the matrix (rows of chosen features)."""

    def __init__(self, table: _DiscreteFeatures):
        self.table = table

    def __getitem__(self, feature: int) -> np.ndarray:
        return self.table.feature_su_row(int(feature))

    def representatives(self, features: np.ndarray) -> np.ndarray:
        """Mask over ``features``: those whose partition no lower-indexed one of them already has.

        Two features are exact copies (SU = 1) exactly when their bins partition the samples the same
        way; comparing partitions (bins renamed in order of first appearance) finds them without SU rows.
        """
        codes = self.table.codes[:, features]
        values = np.arange(int(codes.max(initial=0)) + 1)[:, None, None]
        is_value = codes[None, :, :] == values  # (value, sample, feature)
        first_seen = np.where(is_value.any(axis=1), is_value.argmax(axis=1), codes.shape[0])
        rank_of_value = np.argsort(np.argsort(first_seen, axis=0, kind="stable"), axis=0, kind="stable")
        canonical = np.take_along_axis(rank_of_value, codes, axis=0).T.astype(np.int16)  # bins renamed
        seen: set[bytes] = set()
        keep = np.zeros(len(features), dtype=bool)
        for column, partition in enumerate(canonical):
            signature = partition.tobytes()
            keep[column] = signature not in seen
            seen.add(signature)
        return keep


def _prepare(X, y, n_bins) -> tuple[_DiscreteFeatures, np.ndarray]:
    features = _as_feature_matrix(X)
    class_codes = _encode_labels(y, features.shape[0])
    return _DiscreteFeatures(features, n_bins), class_codes


def information_gain(X, y, *, n_bins: int | None = None) -> np.ndarray:
    """Plug-in I(Y|f) = H(Y) - H(Y | f) in bits per feature (eq. 5.1); 0 if f or y is constant."""
    table, class_codes = _prepare(X, y, n_bins)
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
    significance = _check_significance(significance)
    table, class_codes = _prepare(X, y, n_bins)
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
    significance = _check_significance(significance)
    table, class_codes = _prepare(X, y, n_bins)
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
    significance = _check_significance(significance)
    features = _as_feature_matrix(X)
    indices = np.asarray(subset)
    if indices.ndim != 1 or indices.size == 0 or indices.dtype.kind not in "iu":
        raise ValueError(f"subset must be a non-empty 1-D sequence of integer feature indices; got {subset!r}")
    if np.any(indices < 0) or np.any(indices >= features.shape[1]) or np.unique(indices).size != indices.size:
        raise ValueError(f"subset must hold distinct indices in [0, {features.shape[1] - 1}]; got {indices.tolist()}")
    table, class_codes = _prepare(features[:, indices], y, n_bins)
    return merit_from_correlations(table.class_su(class_codes, significance), table.feature_su)


def _tolerance(merit: float) -> float:
    return _RELATIVE_TOLERANCE * max(1.0, abs(merit))


def _representatives(feature_su: np.ndarray) -> np.ndarray:
    """Mask of features that copy no lower-indexed feature (SU = 1: same partition).

    Doubling every feature of a subset leaves its merit unchanged, a plateau
    greedy elimination cannot cross, so the search sees one member per copy group.
    """
    return ~np.triu(feature_su >= 1.0 - _COPY_TOLERANCE, k=1).any(axis=0)


def _forward(class_su: np.ndarray, feature_su, max_features: int | None) -> np.ndarray:
    """Greedy CFS forward search; ``feature_su`` is the SU matrix or ``_LazyCorrelations`` (rows on demand)."""
    n_features = class_su.size
    if not np.any(class_su > 0):
        return np.arange(n_features)
    # Only features with r_cf > 0 can raise the merit (a zero adds nothing above the line and grows the
    # denominator), and an exact copy has the same r_cf as its original: look for copies among those.
    relevant = np.flatnonzero(class_su > 0)
    if isinstance(feature_su, _LazyCorrelations):
        # Copies have the same SU with the class (up to rounding): look for them only if two values meet.
        may_copy = np.any(np.diff(np.sort(class_su[relevant])) < _COPY_TOLERANCE)
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
    _check_count(max_features, "max_features", 1)
    significance = _check_significance(significance)
    table, class_codes = _prepare(X, y, n_bins)
    return _forward(table.class_su(class_codes, significance), _LazyCorrelations(table), max_features)


def backward_elimination(X, y, *, significance: float = DEFAULT_SIGNIFICANCE, n_bins: int | None = None) -> np.ndarray:
    """ER (§5.3.1): greedy backward elimination on the CFS merit (eq. 5.2); sorted indices.

    From all features (one per group of exact copies), removes the one whose removal
    raises the merit most while it does not fall (ties favour the smaller subset);
    at least one stays. If no feature passes the chance test, all are returned.
    """
    significance = _check_significance(significance)
    table, class_codes = _prepare(X, y, n_bins)
    return _backward(table.class_su(class_codes, significance), table.feature_su)


def _select(table: _DiscreteFeatures, class_codes: np.ndarray, method: str, significance: float) -> np.ndarray:
    if method == "FI":
        chosen = np.flatnonzero(table.chance_corrected_gains(class_codes, significance) > 0.0)
        if chosen.size:
            return chosen
    if method == "ES":
        return _forward(table.class_su(class_codes, significance), _LazyCorrelations(table), None)
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
    significance = _check_significance(significance)
    table, class_codes = _prepare(X, y, n_bins)
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
    significance = _check_significance(significance)
    features = _as_feature_matrix(X)
    label_list = labels.tolist() if isinstance(labels, np.ndarray) else list(labels)
    if len(label_list) != features.shape[0]:
        raise ValueError(f"labels has {len(label_list)} entries but X has {features.shape[0]} rows; they must match")
    table = _DiscreteFeatures(features, n_bins)
    subsets: dict[Hashable, np.ndarray] = {}
    for concept in concepts:
        is_concept = np.array([label == concept for label in label_list], dtype=np.intp)
        if 0 < is_concept.sum() < is_concept.size:
            subsets[concept] = _select(table, is_concept, name, significance)
        else:
            subsets[concept] = np.arange(features.shape[1])
    return subsets
