"""Binary Gaussian-process classifier with an RBF kernel (thesis §6.3, chapters 6-7).

Laplace approximation to the posterior over latent values with a logistic
likelihood (Rasmussen & Williams, *Gaussian Processes for Machine Learning*,
algorithms 3.1 and 3.2), and the probit approximation of the predictive
probability. Written in plain numpy so that the what-if engines can reuse its
pieces. Hyperparameters are fixed, not optimised: with a handful of examples
per concept, marginal-likelihood optimisation is unstable, and a fixed kernel
on standardised features makes every refit cheap and deterministic.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_factor, cho_solve


def rbf_kernel(A: np.ndarray, B: np.ndarray, length_scale: float, variance: float) -> np.ndarray:
    """k(a, b) = variance * exp(-|a - b|^2 / (2 length_scale^2))."""
    sq = (A * A).sum(1)[:, None] + (B * B).sum(1)[None, :] - 2.0 * A @ B.T
    return variance * np.exp(-np.maximum(sq, 0.0) / (2.0 * length_scale**2))


def default_length_scale(n_features: int) -> float:
    """On standardised features the typical squared distance is 2|F|; scale with sqrt(|F|)."""
    return float(np.sqrt(max(n_features, 1)))


class BinaryGPClassifier:
    """p(y = 1 | x) for one concept; sensible with no or one-class data (falls back to the prior)."""

    def __init__(self, length_scale: float | None = None, variance: float = 4.0, max_newton_steps: int = 30,
                 tolerance: float = 1e-6):
        self.length_scale = length_scale
        self.variance = variance
        self.max_newton_steps = max_newton_steps
        self.tolerance = tolerance

    def fit(self, X: np.ndarray, y: np.ndarray) -> BinaryGPClassifier:
        """Fit on rows ``X`` with labels ``y`` in {0, 1} (or booleans)."""
        X = np.asarray(X, dtype=float)
        y = np.asarray(y).astype(float).ravel()
        if X.ndim != 2 or len(X) != len(y):
            raise ValueError(f"X must be 2-D with one row per label; got X {X.shape}, y {y.shape}")
        self.X_train_ = X
        self.length_scale_ = self.length_scale or default_length_scale(X.shape[1])
        self.targets_ = 2.0 * y - 1.0  # {-1, +1}
        if len(y) == 0:
            self.f_hat_ = np.zeros(0)
            return self
        K = rbf_kernel(X, X, self.length_scale_, self.variance)
        self.f_hat_, self.W_sqrt_, self.L_ = self._newton(K, self.targets_)
        self.grad_ = (self.targets_ + 1) / 2 - sigmoid(self.f_hat_)  # d log p(y|f) / df at the mode
        return self

    def _newton(self, K: np.ndarray, t: np.ndarray):
        """Mode of p(f | X, y) by Newton's method (R&W algorithm 3.1)."""
        n = len(t)
        f = np.zeros(n)
        for _ in range(self.max_newton_steps):
            pi = sigmoid(f)
            W = pi * (1 - pi)
            sw = np.sqrt(W)
            B = np.eye(n) + sw[:, None] * K * sw[None, :]
            L = cho_factor(B, lower=True)
            grad = (t + 1) / 2 - pi
            b = W * f + grad
            a = b - sw * cho_solve(L, sw * (K @ b))
            f_new = K @ a
            if np.max(np.abs(f_new - f)) < self.tolerance:
                f = f_new
                break
            f = f_new
        pi = sigmoid(f)
        sw = np.sqrt(pi * (1 - pi))
        L = cho_factor(np.eye(n) + sw[:, None] * K * sw[None, :], lower=True)
        return f, sw, L

    def latent(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predictive mean and variance of the latent function (R&W algorithm 3.2)."""
        X = np.asarray(X, dtype=float)
        if len(self.targets_) == 0:
            return np.zeros(len(X)), np.full(len(X), self.variance)
        Ks = rbf_kernel(self.X_train_, X, self.length_scale_, self.variance)
        mean = Ks.T @ self.grad_
        v = cho_solve(self.L_, self.W_sqrt_[:, None] * Ks)
        var = self.variance - np.sum((self.W_sqrt_[:, None] * Ks) * v, axis=0)
        return mean, np.maximum(var, 1e-12)

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """p(y = 1 | x) by the probit approximation sigma(mu / sqrt(1 + pi var / 8))."""
        mean, var = self.latent(X)
        return sigmoid(mean / np.sqrt(1.0 + np.pi * var / 8.0))


def sigmoid(z: np.ndarray) -> np.ndarray:
    """The logistic function 1 / (1 + exp(-z)), written with tanh so it never overflows."""
    return 0.5 * (1.0 + np.tanh(0.5 * z))
