"""The information-theory pieces of feature selection (thesis §5.3): discretisation, entropies, gains and
symmetrical uncertainties on a discretised feature table. The choices are listed in
``learning.features.selection``; this module only computes.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.special import gammaincinv

DEFAULT_SIGNIFICANCE = 0.05
MAX_DEFAULT_BINS = 10
COPY_TOLERANCE = 1e-9


@lru_cache(maxsize=4096)
def _chi2_quantile(probability: float, degrees: int) -> float:
    """The chi-squared quantile, computed as ``scipy.stats.chi2.ppf`` computes it (2 * gammaincinv(df / 2, p)),
    without importing scipy.stats: that import is about half of every ``teachbot`` process's start-up."""
    return float(2 * gammaincinv(degrees / 2, probability))


def _chi2_quantiles(probability: float, degrees: np.ndarray) -> np.ndarray:
    """chi2.ppf for an array of (few distinct) degrees of freedom, each computed once."""
    distinct, inverse = np.unique(degrees, return_inverse=True)
    return np.array([_chi2_quantile(probability, int(d)) for d in distinct])[inverse.reshape(-1)]


def default_bin_count(n_samples: int) -> int:
    """Equal-frequency bins used for ``n_samples``: ceil(cbrt(n)) clipped to [2, 10]."""
    cube_root = round(max(n_samples, 1) ** (1.0 / 3.0), 9)
    return int(min(MAX_DEFAULT_BINS, max(2, math.ceil(cube_root))))


def as_feature_matrix(X) -> np.ndarray:
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


def check_significance(significance: float) -> float:
    if isinstance(significance, bool) or not isinstance(significance, (int, float)) or not 0 < significance < 1:
        raise ValueError(f"significance must be a number strictly between 0 and 1; got {significance!r}")
    return float(significance)


def check_count(value, name: str, minimum: int) -> None:
    if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum):
        raise ValueError(f"{name} must be None or an integer >= {minimum}; got {value!r}")



def _discretize(features: np.ndarray, n_bins: int) -> np.ndarray:
    """Equal-frequency codes for all columns at once (vectorised; see the module docstring)."""
    n_samples, n_features = features.shape
    # Ties may sort in any order: equal values get the same rank and bin whatever their order, so the fast
    # (unstable) sort of the contiguous transposed rows gives the same codes as a stable one, 5x faster.
    order = np.argsort(features.T, axis=1).T
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
    check_count(n_bins, "n_bins", 2)
    features = as_feature_matrix(X)
    return _discretize(features, n_bins or default_bin_count(features.shape[0]))


def _joint_entropies(left: np.ndarray, right: np.ndarray, starts: np.ndarray):
    """Plug-in H(a, b) in bits and occupied cells, one-hot ``left`` vs each block of ``right``.

    ``right`` may be float32: the counts are whole numbers below 2^24, exact in single precision (and the
    product twice as fast).
    """
    counts = (left.T.astype(right.dtype) @ right).astype(np.intp)  # whole numbers: exact in float32
    terms = _entropy_terms(left.shape[0])[counts].sum(axis=0)
    return np.add.reduceat(terms, starts), np.add.reduceat((counts > 0).sum(axis=0), starts)


@lru_cache(maxsize=64)
def _entropy_terms(n_samples: int) -> np.ndarray:
    """-p log2 p for p = c / n, c = 0..n (0 at c = 0): each cell's term looked up by its count, the same
    bits as computing it per cell (the logarithms were about a fifth of one SU row's time)."""
    probabilities = np.arange(n_samples + 1) / max(n_samples, 1)
    terms = -(probabilities * np.log2(np.where(probabilities > 0, probabilities, 1.0)))
    terms.flags.writeable = False
    return terms


def _symmetrical_uncertainty(mutual: np.ndarray, entropy_sums: np.ndarray) -> np.ndarray:
    """SU = 2 I / (H_a + H_b) clipped to [0, 1]; 0 when both variables are constant."""
    safe = np.where(entropy_sums > 0, entropy_sums, 1.0)
    return np.where(entropy_sums > 0, np.clip(2.0 * mutual / safe, 0.0, 1.0), 0.0)


class DiscreteFeatures:
    """Discretised X plus what every selector reuses (entropies, bin sizes, SU matrix)."""

    def __init__(self, features: np.ndarray, n_bins: int | None):
        check_count(n_bins, "n_bins", 2)
        self.n_samples, self.n_features = features.shape
        self.codes = _discretize(features, n_bins or default_bin_count(self.n_samples))
        self.levels = self.codes.max(axis=0) + 1
        self.starts = np.concatenate(([0], np.cumsum(self.levels)[:-1]))
        self.one_hot = np.zeros((self.n_samples, int(self.levels.sum())))
        self.one_hot[np.arange(self.n_samples)[:, None], self.starts + self.codes] = 1.0
        self.one_hot32 = self.one_hot.astype(np.float32)  # what the count products read
        self.entropies = self._entropy(self.one_hot32, self.starts)
        self.inverse_bin_sizes = np.add.reduceat(1.0 / self.one_hot.sum(axis=0), self.starts)
        self._feature_su: np.ndarray | None = None
        self._su_rows: dict[int, np.ndarray] = {}
        self._class_tables: dict[bytes, tuple] = {}
        self._signatures: list[bytes] | None = None

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
            joint, cells = _joint_entropies(class_one_hot, self.one_hot32, self.starts)
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
                joint, cells = _joint_entropies(block, self.one_hot32, self.starts)
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
            joint, cells = _joint_entropies(block, self.one_hot32, self.starts)
            mutual = marginals[feature] + marginals - self._miller_madow(joint, cells)
            row = _symmetrical_uncertainty(mutual, marginals[feature] + marginals)
            row[feature] = 1.0 if marginals[feature] > 0 else 0.0
            self._su_rows[feature] = row
        return self._su_rows[feature]


    def partition_signatures(self) -> list[bytes]:
        """Per feature, its partition of the samples as bytes (bins renamed in order of first appearance).

        Computed once for every feature (ES asks for it once per concept): equal signatures are exact copies.
        """
        if self._signatures is None:
            codes = self.codes
            values = np.arange(int(codes.max(initial=0)) + 1)[:, None, None]
            is_value = codes[None, :, :] == values  # (value, sample, feature)
            first_seen = np.where(is_value.any(axis=1), is_value.argmax(axis=1), codes.shape[0])
            rank_of_value = np.argsort(np.argsort(first_seen, axis=0, kind="stable"), axis=0, kind="stable")
            canonical = np.take_along_axis(rank_of_value, codes, axis=0).T.astype(np.int16)  # bins renamed
            self._signatures = [partition.tobytes() for partition in canonical]
        return self._signatures

class LazyCorrelations:
    """Feature-feature SU rows on demand: what ES reads of the matrix (rows of chosen features)."""

    def __init__(self, table: DiscreteFeatures):
        self.table = table

    def __getitem__(self, feature: int) -> np.ndarray:
        return self.table.feature_su_row(int(feature))

    def representatives(self, features: np.ndarray) -> np.ndarray:
        """Mask over ``features``: those whose partition no lower-indexed one of them already has.

        Two features are exact copies (SU = 1) exactly when their bins partition the samples the same
        way; comparing partitions (bins renamed in order of first appearance) finds them without SU rows.
        """
        signatures = self.table.partition_signatures()
        seen: set[bytes] = set()
        keep = np.zeros(len(features), dtype=bool)
        for column, feature in enumerate(features):
            signature = signatures[int(feature)]
            keep[column] = signature not in seen
            seen.add(signature)
        return keep


def prepare(X, y, n_bins) -> tuple[DiscreteFeatures, np.ndarray]:
    features = as_feature_matrix(X)
    class_codes = _encode_labels(y, features.shape[0])
    return DiscreteFeatures(features, n_bins), class_codes
