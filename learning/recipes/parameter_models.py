"""Gaussian-mixture models of one recipe parameter (thesis §4.2.3, §4.2.4).

Every object parameter (``pasta-pot``) and every location parameter (``stove``)
of a recipe gets one ``ParameterModel``. Object models live on the appearance
features ``(r, g, b, length, width, height)``; location models on the
bounding-box centroid ``(x, y, z)`` relative to the robot.

Hypotheses and selection (§4.2.3). With m demonstrations the model fits m
hypotheses, Gaussian mixtures with k = 1..m full-covariance components, and
keeps the one with the lowest Bayesian Information Criterion

    BIC(k) = -2 log L(k) + p(k) ln n,   p(k) = (k - 1) + k d + k d (d + 1) / 2,

with n samples in d dimensions and log L measured in the original units. k is
also capped at the number of distinct samples and at ``max_components``.

Covariance prior (sensor noise). Every component covariance is the maximum-
likelihood (responsibility-weighted) estimate plus a diagonal noise floor,

    Sigma_j = Sigma_j^ML + diag(noise_std ** 2),

applied in every M-step of EM (a regularised, MAP-style estimate). A component
fitted to a single sample therefore has exactly the sensor-noise covariance,
so one demonstration already gives a usable model. Implementation: k = 1 is
solved in closed form; k >= 2 runs EM from k-means++ seeds (distances scaled
by ``noise_std``), ``n_init`` restarts, keeping the highest log-likelihood.
Every random draw comes from the numpy Generator given to the model.

Distances (§4.2.4). ``mahalanobis`` is the distance to the *nearest* component,
min_j sqrt((x - mu_j)^T Sigma_j^-1 (x - mu_j)), the quantity compared with
tau = 3.0. ``log_likelihood`` is the log density of the whole mixture (eq. 4.3).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.linalg import solve_triangular
from scipy.special import logsumexp

_LOG_TWO_PI = float(np.log(2.0 * np.pi))


class ParameterModel:
    """GMM over one parameter's features with BIC choice of k = 1..m (thesis §4.2.3).

    ``noise_std``: sensor-noise standard deviation, a positive scalar or one
    value per feature; it is the covariance floor described in the module doc.
    ``max_components``: optional extra cap on k. ``rng``: numpy Generator that
    seeds every EM run (default ``numpy.random.default_rng(0)``).
    """

    def __init__(
        self,
        noise_std: float | Sequence[float] | np.ndarray,
        max_components: int | None = None,
        rng: np.random.Generator | None = None,
        *,
        n_init: int = 2,
    ) -> None:
        noise = np.atleast_1d(np.asarray(noise_std, dtype=float))
        if noise.ndim != 1 or noise.size == 0 or not np.all(np.isfinite(noise)) or np.any(noise <= 0):
            raise ValueError(f"noise_std must be a positive finite number or a 1-D array of them, got {noise_std!r}")
        if max_components is not None and (not isinstance(max_components, (int, np.integer)) or max_components < 1):
            raise ValueError(f"max_components must be None or an integer >= 1, got {max_components!r}")
        if rng is not None and not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator or None, got {type(rng).__name__}")
        if not isinstance(n_init, (int, np.integer)) or n_init < 1:
            raise ValueError(f"n_init must be an integer >= 1, got {n_init!r}")
        self.noise_std = noise
        self.max_components = None if max_components is None else int(max_components)
        self.n_init = int(n_init)
        self._rng = rng if rng is not None else np.random.default_rng(0)
        self.samples_: np.ndarray | None = None
        self.n_demonstrations_ = 0
        self.weights_: np.ndarray | None = None
        self.means_: np.ndarray | None = None
        self.covariances_: np.ndarray | None = None
        self.bic_per_k_: dict[int, float] = {}

    # ------------------------------------------------------------------ fitting
    def fit(self, samples: np.ndarray, n_demonstrations: int | None = None) -> ParameterModel:
        """Fit hypotheses k = 1..m and keep the best by BIC (thesis §4.2.3).

        ``samples`` is (n x d). ``n_demonstrations`` is m, the number of
        demonstrations the samples came from (default: one per sample).
        """
        data = self._checked_samples(samples, "samples")
        if n_demonstrations is None:
            n_demonstrations = data.shape[0]
        if not isinstance(n_demonstrations, (int, np.integer)) or n_demonstrations < 1:
            raise ValueError(f"n_demonstrations must be an integer >= 1, got {n_demonstrations!r}")
        self.samples_ = data
        self.n_demonstrations_ = int(n_demonstrations)
        self._refit()
        return self

    def add(self, samples: np.ndarray) -> ParameterModel:
        """Add the samples of one more demonstration (one row or n x d) and refit."""
        new = self._checked_samples(np.atleast_2d(np.asarray(samples, dtype=float)), "sample")
        if self.samples_ is None:
            return self.fit(new, n_demonstrations=1)
        if new.shape[1] != self.samples_.shape[1]:
            raise ValueError(f"sample has {new.shape[1]} features; this model was fitted on {self.samples_.shape[1]}")
        self.samples_ = np.vstack([self.samples_, new])
        self.n_demonstrations_ += 1
        self._refit()
        return self

    @property
    def is_fitted(self) -> bool:
        return self.means_ is not None

    @property
    def n_components_(self) -> int:
        """k of the hypothesis chosen by BIC."""
        _, means, _ = self._fitted()
        return int(means.shape[0])

    @property
    def dimension_(self) -> int:
        _, means, _ = self._fitted()
        return int(means.shape[1])

    def candidate_component_counts(self) -> list[int]:
        """The k values tried: 1..min(m, distinct samples, max_components)."""
        if self.samples_ is None:
            return []
        distinct = np.unique(self.samples_, axis=0).shape[0]
        limit = min(self.n_demonstrations_, distinct)
        if self.max_components is not None:
            limit = min(limit, self.max_components)
        return list(range(1, max(limit, 1) + 1))

    def _refit(self) -> None:
        data = self.samples_
        assert data is not None, "_refit runs only after samples_ is set"
        noise = self._noise_for(data.shape[1])
        best: tuple[float, np.ndarray, np.ndarray, np.ndarray] | None = None
        self.bic_per_k_ = {}
        for k in self.candidate_component_counts():
            weights, means, covariances = (
                self._fit_one_component(data, noise) if k == 1 else self._fit_mixture(data, noise, k)
            )
            log_l = float(np.sum(_mixture_log_density(data, weights, means, covariances)))
            bic = -2.0 * log_l + _free_parameter_count(k, data.shape[1]) * np.log(data.shape[0])
            self.bic_per_k_[k] = float(bic)
            if best is None or bic < best[0]:
                best = (bic, weights, means, covariances)
        assert best is not None, "candidate_component_counts() is never empty once samples_ is set"
        _, self.weights_, self.means_, self.covariances_ = best

    @staticmethod
    def _fit_one_component(data: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        mean = data.mean(axis=0)
        centred = data - mean
        covariance = centred.T @ centred / data.shape[0] + np.diag(noise**2)
        return np.ones(1), mean[None, :], covariance[None, :, :]

    def _fit_mixture(self, data: np.ndarray, noise: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Best of ``n_init`` EM runs (highest log-likelihood), floor added every M-step."""
        best: tuple[float, np.ndarray, np.ndarray, np.ndarray] | None = None
        for _ in range(self.n_init):
            weights, means, covariances, log_l = _floored_em(data, noise, k, self._rng)
            if best is None or log_l > best[0]:
                best = (log_l, weights, means, covariances)
        assert best is not None, "n_init >= 1 is checked in __init__"
        _, weights, means, covariances = best
        order = np.lexsort(means.T[::-1])  # report components in a stable order
        return weights[order], means[order], covariances[order]

    # --------------------------------------------------------------- evaluation
    def mahalanobis(self, points: np.ndarray) -> np.ndarray:
        """Distance of each point to the nearest component (compare with tau, §4.2.4)."""
        queries = self._checked_points(points)
        _, means, covariances = self._fitted()
        squared, _ = _squared_mahalanobis_and_log_dets(queries, means, covariances)
        return np.sqrt(squared.min(axis=1))

    def log_likelihood(self, points: np.ndarray) -> np.ndarray:
        """Log density of each point under the whole mixture (eq. 4.3)."""
        queries = self._checked_points(points)
        return _mixture_log_density(queries, *self._fitted())

    def heaviest_component_mean(self) -> np.ndarray:
        """Mean of the component with the largest weight (ties: the first)."""
        weights, means, _ = self._fitted()
        return means[int(np.argmax(weights))].copy()

    # ------------------------------------------------------------------ helpers
    def _noise_for(self, dimension: int) -> np.ndarray:
        if self.noise_std.size == 1:
            return np.full(dimension, float(self.noise_std[0]))
        if self.noise_std.size != dimension:
            raise ValueError(
                f"samples have {dimension} features but noise_std has {self.noise_std.size} "
                "values; give one noise value per feature or a single number"
            )
        return self.noise_std

    def _checked_samples(self, samples: np.ndarray, what: str) -> np.ndarray:
        data = np.asarray(samples, dtype=float)
        if data.ndim != 2 or data.shape[0] == 0 or data.shape[1] == 0:
            raise ValueError(f"{what} must be a non-empty 2-D array (n samples x d features), got shape {data.shape}")
        if not np.all(np.isfinite(data)):
            raise ValueError(f"{what} contain NaN or infinite values; accepted: finite numbers")
        self._noise_for(data.shape[1])
        return data.copy()

    def _checked_points(self, points: np.ndarray) -> np.ndarray:
        self._fitted()
        queries = np.atleast_2d(np.asarray(points, dtype=float))
        if queries.ndim != 2 or queries.shape[1] != self.dimension_:
            raise ValueError(
                f"points must have {self.dimension_} features per row, got shape {np.asarray(points).shape}"
            )
        if not np.all(np.isfinite(queries)):
            raise ValueError("points contain NaN or infinite values; accepted: finite numbers")
        return queries

    def _fitted(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The chosen mixture's (weights, means, covariances); a ValueError before any data."""
        if self.weights_ is None or self.means_ is None or self.covariances_ is None:
            raise ValueError("this ParameterModel has no data yet; call fit(samples) or add(sample)")
        return self.weights_, self.means_, self.covariances_

    def __repr__(self) -> str:
        if not self.is_fitted or self.samples_ is None:
            return "ParameterModel(unfitted)"
        return (
            f"ParameterModel(k={self.n_components_}, d={self.dimension_}, "
            f"n={self.samples_.shape[0]}, m={self.n_demonstrations_})"
        )


def _free_parameter_count(k: int, d: int) -> int:
    """Mixture weights, means and full covariances of k components in d dimensions."""
    return (k - 1) + k * d + k * d * (d + 1) // 2


def _squared_mahalanobis_and_log_dets(
    points: np.ndarray, means: np.ndarray, covariances: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(n x k) squared Mahalanobis distances to each component, and each log |Sigma_j|."""
    squared = np.empty((points.shape[0], means.shape[0]))
    log_dets = np.empty(means.shape[0])
    for j, (mean, covariance) in enumerate(zip(means, covariances)):
        cholesky = np.linalg.cholesky(covariance)
        whitened = solve_triangular(cholesky, (points - mean).T, lower=True)
        squared[:, j] = np.sum(whitened**2, axis=0)
        log_dets[j] = 2.0 * np.sum(np.log(np.diag(cholesky)))
    return squared, log_dets


def _component_log_densities(points: np.ndarray, means: np.ndarray, covariances: np.ndarray) -> np.ndarray:
    """(n x k) log N(x | mu_j, Sigma_j)."""
    squared, log_dets = _squared_mahalanobis_and_log_dets(points, means, covariances)
    return -0.5 * (points.shape[1] * _LOG_TWO_PI + log_dets[None, :] + squared)


def _mixture_log_density(
    points: np.ndarray, weights: np.ndarray, means: np.ndarray, covariances: np.ndarray
) -> np.ndarray:
    """log sum_j w_j N(x | mu_j, Sigma_j) for each point."""
    return logsumexp(_component_log_densities(points, means, covariances) + np.log(weights), axis=1)


def _floored_em(
    data: np.ndarray,
    noise: np.ndarray,
    k: int,
    rng: np.random.Generator,
    max_iter: int = 200,
    tolerance: float = 1e-7,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """One EM run for a k-component GMM with the noise floor in each M-step."""
    floor = np.diag(noise**2)
    centres = _kmeans_plus_plus_seeds(data / noise, k, rng) * noise
    nearest = np.argmin((((data[:, None, :] - centres[None, :, :]) / noise) ** 2).sum(axis=2), axis=1)
    responsibilities = np.eye(k)[nearest]
    means = centres.copy()
    previous = -np.inf
    for _ in range(max_iter):
        weights, means, covariances = _floored_m_step(data, responsibilities, means, floor)
        component_log = _component_log_densities(data, means, covariances) + np.log(weights)
        point_log = logsumexp(component_log, axis=1)
        responsibilities = np.exp(component_log - point_log[:, None])
        log_l = float(point_log.sum())
        if log_l - previous < tolerance * data.shape[0]:
            break
        previous = log_l
    return weights, means, covariances, log_l


def _floored_m_step(
    data: np.ndarray, responsibilities: np.ndarray, old_means: np.ndarray, floor: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    counts = responsibilities.sum(axis=0)
    weights = np.maximum(counts, 1e-12) / data.shape[0]
    weights /= weights.sum()
    means = old_means.copy()
    covariances = np.repeat(floor[None, :, :], len(counts), axis=0)
    for j, count in enumerate(counts):
        if count < 1e-10:  # an emptied component keeps its mean and the noise covariance
            continue
        means[j] = responsibilities[:, j] @ data / count
        centred = data - means[j]
        covariances[j] += (responsibilities[:, j, None] * centred).T @ centred / count
    return weights, means, covariances


def _kmeans_plus_plus_seeds(scaled: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """k distinct seed points, each drawn with probability proportional to squared distance."""
    seeds = [scaled[rng.integers(scaled.shape[0])]]
    for _ in range(1, k):
        squared = np.min(((scaled[:, None, :] - np.array(seeds)[None]) ** 2).sum(axis=2), axis=1)
        total = squared.sum()
        if total <= 0:
            break
        seeds.append(scaled[rng.choice(scaled.shape[0], p=squared / total)])
    while len(seeds) < k:  # only reached with fewer distinct points than k
        seeds.append(seeds[-1])
    return np.array(seeds)
