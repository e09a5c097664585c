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

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cholesky, solve_triangular
from scipy.linalg.lapack import dpotrf, dpotrs, spotrf, spotrs, strtrs


def rbf_kernel(A: np.ndarray, B: np.ndarray, length_scale: float, variance: float) -> np.ndarray:
    """k(a, b) = variance * exp(-|a - b|^2 / (2 length_scale^2))."""
    sq = (A * A).sum(1)[:, None] + (B * B).sum(1)[None, :] - 2.0 * A @ B.T
    return variance * np.exp(-np.maximum(sq, 0.0) / (2.0 * length_scale**2))


def default_length_scale(n_features: int) -> float:
    """On standardised features the typical squared distance is 2|F|; scale with sqrt(|F|)."""
    return float(np.sqrt(max(n_features, 1)))


# Below this many examples a fresh fit is cheaper than an update (Python overhead; scripts/bench_refit.py).
INCREMENTAL_FROM = 100


class BinaryGPClassifier:
    """p(y = 1 | x) for one concept; sensible with no or one-class data (falls back to the prior)."""

    K_: np.ndarray  # the training kernel, kept so that an answer's refit only computes the new rows

    def __init__(self, length_scale: float | None = None, variance: float = 4.0, max_newton_steps: int = 30,
                 tolerance: float = 1e-6, incremental_from: int = INCREMENTAL_FROM):
        self.length_scale = length_scale
        self.variance = variance
        self.max_newton_steps = max_newton_steps
        self.tolerance = tolerance
        self.incremental_from = incremental_from

    def fit(self, X: np.ndarray, y: np.ndarray, previous: BinaryGPClassifier | None = None,
            kernel: np.ndarray | None = None, defer_newton: bool = False) -> BinaryGPClassifier:
        """Fit on rows ``X`` with labels ``y`` in {0, 1} (or booleans).

        ``previous``: an earlier fit of this kind. When ``X`` and ``y`` only append rows to its training set
        (same kernel, same rows before them), the fit is updated instead of redone (``_extend``): its kernel
        is reused and Newton starts at its mode. The result equals a fresh fit within the Newton tolerance.
        ``kernel``: ``rbf_kernel(X, X)`` as another classifier on the same rows and kernel already computed it
        (the same bits); a fresh fit uses it instead of computing it again, is never written to it.
        ``defer_newton``: a fresh fit stops before Newton (``pending_`` True); ``fit_together`` then finds
        the modes of several such fits on one kernel at once.
        """
        X = np.asarray(X, dtype=float)
        y = np.asarray(y).astype(float).ravel()
        if X.ndim != 2 or len(X) != len(y):
            raise ValueError(f"X must be 2-D with one row per label; got X {X.shape}, y {y.shape}")
        self.X_train_ = X
        self.length_scale_ = self.length_scale or default_length_scale(X.shape[1])
        self.targets_ = 2.0 * y - 1.0  # {-1, +1}
        self.incremental_ = self.pending_ = False
        if len(y) == 0:
            self.f_hat_ = np.zeros(0)
            return self
        if previous is not None and self._extends(previous):
            self.K_ = extended_kernel(previous.K_, previous.X_train_, X[len(previous.targets_):],
                                      self.length_scale_, self.variance)
            self.f_hat_, self.W_sqrt_, self.L_ = self._extend(previous, self.K_, self.targets_)
            self.incremental_ = True
        else:
            if kernel is not None and kernel.shape != (len(X), len(X)):
                raise ValueError(f"kernel must be ({len(X)}, {len(X)}) for {len(X)} rows, got {kernel.shape}")
            self.K_ = rbf_kernel(X, X, self.length_scale_, self.variance) if kernel is None else kernel
            if defer_newton:
                self.pending_ = True
                return self
            self.f_hat_, self.W_sqrt_, self.L_ = self._newton(self.K_, self.targets_)
        self.grad_ = (self.targets_ + 1) / 2 - sigmoid(self.f_hat_)  # d log p(y|f) / df at the mode
        return self

    @staticmethod
    def fit_together(models: list[BinaryGPClassifier]) -> None:
        """Finish fresh fits left ``pending_`` on one shared kernel: their Newton steps as one batch
        (``newton_modes``), each model's bits as its own ``_newton`` would give them."""
        first = models[0]
        f, sw = newton_modes(first.K_, np.stack([m.targets_ for m in models]), first.max_newton_steps,
                             first.tolerance)
        for model, f_hat, w_sqrt in zip(models, f, sw):
            model.f_hat_, model.W_sqrt_, model.L_ = f_hat, w_sqrt, mode_factor(model.K_, w_sqrt)
            model.grad_ = (model.targets_ + 1) / 2 - sigmoid(model.f_hat_)
            model.pending_ = False

    def _extends(self, previous: BinaryGPClassifier) -> bool:
        """Whether this fit's training set is ``previous``'s with rows appended, under the same kernel."""
        n_old = len(getattr(previous, "targets_", ()))
        return (max(1, self.incremental_from) <= n_old < len(self.targets_)
                and getattr(previous, "K_", None) is not None and previous.X_train_.shape[1] == self.X_train_.shape[1]
                and previous.length_scale_ == self.length_scale_ and previous.variance == self.variance
                and np.array_equal(previous.targets_, self.targets_[:n_old])
                and np.array_equal(previous.X_train_, self.X_train_[:n_old]))

    def _extend(self, previous: BinaryGPClassifier, K: np.ndarray, t: np.ndarray):
        """The mode after appending sites to ``previous``'s fit, in O(n^2) per step, then the factor at the mode.

        Start: the old sites at the old mode (a = its gradient) and each new site at its predictive mean
        given them (f = K a). Chord Newton steps a <- a + (I + W0 K)^-1 (grad - a) solve with the old
        factor bordered by the new rows (exact for B0 = I + S0 K S0, S0 the old W^1/2 and the new sites'
        at the start): two triangular solves and two products with K per step. The fixed point is the
        mode itself; only the rate depends on how far W moved from W0. If the steps stop shrinking, Newton
        with a fresh factor per step takes over (``_newton`` from the current point). The predictive
        variance needs B at the mode, so its factor is computed once at the end.
        """
        n_old = len(previous.targets_)
        a = np.concatenate([previous.grad_, np.zeros(len(t) - n_old)])
        f = K @ a
        pi = sigmoid(f[n_old:])
        sw0 = np.concatenate([previous.W_sqrt_, np.sqrt(pi * (1 - pi))])
        factor = BorderedFactor.of(previous.L_[0], K, sw0)
        last = np.inf
        for _ in range(self.max_newton_steps):
            r = (t + 1) / 2 - sigmoid(f) - a
            Kr = K @ r
            solved = sw0 * factor.solve(sw0 * Kr)
            step_f = Kr - K @ solved
            a += r - solved
            f += step_f
            size = float(np.max(np.abs(step_f)))
            if size < CHORD_TOLERANCE * self.tolerance:
                break
            if size > CHORD_CONTRACTION * last:  # W moved too far for the old factor: refactor every step
                return self._newton(K, t, start=f)
            last = size
        else:
            return self._newton(K, t, start=f)
        pi = sigmoid(f)
        sw = np.sqrt(pi * (1 - pi))
        return f, sw, mode_factor(K, sw)

    def _newton(self, K: np.ndarray, t: np.ndarray, start: np.ndarray | None = None):
        """Mode of p(f | X, y) by Newton's method (R&W algorithm 3.1), from f = 0 unless ``start`` is given."""
        f, sw = newton_modes(K, t[None], self.max_newton_steps, self.tolerance,
                             None if start is None else start[None])
        return f[0], sw[0], mode_factor(K, sw[0])

    def latent(self, X: np.ndarray, cross: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Predictive mean and variance of the latent function (R&W algorithm 3.2); ``cross`` is
        ``rbf_kernel(X_train_, X)`` when a classifier on the same training rows already computed it."""
        X = np.asarray(X, dtype=float)
        if len(self.targets_) == 0:
            return np.zeros(len(X)), np.full(len(X), self.variance)
        Ks = rbf_kernel(self.X_train_, X, self.length_scale_, self.variance) if cross is None else cross
        mean = Ks.T @ self.grad_
        right = self.W_sqrt_[:, None] * Ks
        v = factor_solve(self.L_[0], right.astype(np.float32))  # B^-1 S K_ns (float32: see mode_factor)
        var = self.variance - np.sum(right * v, axis=0)
        return mean, np.maximum(var, 1e-12)

    def predict_proba(self, X: np.ndarray, cross: np.ndarray | None = None) -> np.ndarray:
        """p(y = 1 | x) by the probit approximation sigma(mu / sqrt(1 + pi var / 8)) (``cross``: see ``latent``)."""
        mean, var = self.latent(X, cross)
        return sigmoid(mean / np.sqrt(1.0 + np.pi * var / 8.0))


def newton_modes(K: np.ndarray, targets: np.ndarray, max_steps: int, tolerance: float,
                 start: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Modes f (g, n) and W^1/2 at them of p(f | X, y) for label rows ``targets`` (g, n) in {-1, +1} sharing
    the kernel K, by Newton's method (R&W algorithm 3.1) from 0 or ``start``; a row stops once its latent
    values move by less than ``tolerance``. The elementwise steps run on all rows at once; each row's
    products with K and its Cholesky calls are its own, so every row gets the bits of a fit alone.
    """
    g, n = targets.shape
    f = np.zeros((g, n)) if start is None else np.array(start, dtype=float)
    positive = (targets + 1) / 2
    active = np.arange(g)
    for _ in range(max_steps):
        f_now = f if len(active) == g else f[active]
        pi = sigmoid(f_now)
        W = pi * (1 - pi)
        sw = np.sqrt(W)
        B = np.multiply(sw[:, :, None], K)  # B = I + S K S, built in place: the bits of eye(n) + sw K sw
        B *= sw[:, None, :]
        B.reshape(len(active), n * n)[:, :: n + 1] += 1.0
        grad = positive[active] - pi
        b = W * f_now + grad
        right = np.empty_like(b)
        for row in range(len(active)):
            right[row] = K @ b[row]
        right *= sw
        for row in range(len(active)):
            right[row] = dense_solve(dense_factor(B[row]), right[row])
        right *= sw
        a = b - right
        f_new = np.empty_like(a)
        for row in range(len(active)):
            f_new[row] = K @ a[row]
        moved = np.max(np.abs(f_new - f_now), axis=1)
        f[active] = f_new
        active = active[moved >= tolerance]
        if len(active) == 0:
            break
    pi = sigmoid(f)
    return f, np.sqrt(pi * (1 - pi))


# The chord steps of an incremental refit stop once the latent values move by less than this fraction of the
# Newton tolerance (a fresh fit's last step is below the tolerance itself; its error is far below it), and
# give way to full Newton if a step is not at least this much smaller than the one before.
CHORD_TOLERANCE = 1e-3
CHORD_CONTRACTION = 0.5


def extended_kernel(K: np.ndarray, X_old: np.ndarray, X_new: np.ndarray, length_scale: float,
                    variance: float) -> np.ndarray:
    """K over the old rows then ``X_new``, reusing the old block: O(n k d) new entries instead of O(n^2 d)."""
    n_old, n = len(X_old), len(X_old) + len(X_new)
    extended = np.empty((n, n))
    extended[:n_old, :n_old] = K
    across = rbf_kernel(X_old, X_new, length_scale, variance)
    extended[:n_old, n_old:] = across
    extended[n_old:, :n_old] = across.T
    extended[n_old:, n_old:] = rbf_kernel(X_new, X_new, length_scale, variance)
    return extended


@dataclass(frozen=True)
class BorderedFactor:
    """The lower Cholesky factor of I + S K S (S = diag(sw)) from ``L_old``, the factor of its leading block.

    The new rows: L21 = (L_old^-1 S1 K12 S2)^T and L22 = chol(I + S2 K22 S2 - L21 L21^T), O(n^2 k) for k
    new rows; ``L_old`` is used in place (no copy of the n x n factor), solves go block by block.
    """

    old: np.ndarray  # L_old, lower (only its lower triangle is read)
    border: np.ndarray  # L21^T, (n_old, k)
    corner: np.ndarray  # L22, lower (k, k)

    @classmethod
    def of(cls, L_old: np.ndarray, K: np.ndarray, sw: np.ndarray) -> BorderedFactor:
        n_old = len(L_old)
        s_old, s_new = sw[:n_old], sw[n_old:]
        right = (s_old[:, None] * K[:n_old, n_old:] * s_new[None, :]).astype(np.float32)
        border = triangular_solve(L_old, right, lower=True, trans=0).astype(float)
        corner = np.eye(len(s_new)) + s_new[:, None] * K[n_old:, n_old:] * s_new[None, :] - border.T @ border
        return cls(L_old, border, cholesky(corner, lower=True, check_finite=False))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """(L L^T)^-1 b, forward then back substitution by blocks (the old block in float32: a preconditioner)."""
        n_old = len(self.old)
        top = triangular_solve(self.old, b[:n_old].astype(np.float32), lower=True, trans=0).astype(float)
        bottom = solve_triangular(self.corner, b[n_old:] - self.border.T @ top, lower=True, check_finite=False)
        bottom = solve_triangular(self.corner, bottom, lower=True, trans="T", check_finite=False)
        top = triangular_solve(self.old, (top - self.border @ bottom).astype(np.float32), lower=True, trans=1)
        return np.concatenate([top.astype(float), bottom])


def mode_factor(K: np.ndarray, sw: np.ndarray) -> tuple[np.ndarray, bool]:
    """The lower Cholesky factor of B = I + S K S at the mode (S = diag(sw)), in float32, as (factor, True).

    B's eigenvalues are >= 1 and at most 1 + n max(W) variance, so single precision moves the predictive
    probabilities by ~1e-8 (tests/learning/test_gp.py), far inside the Newton tolerance, and LAPACK's
    float32 factorisation takes about half the time: it is the O(n^3) step of every refit.
    """
    B = np.empty(K.shape, dtype=np.float32)
    np.multiply(K, sw[:, None], out=B, casting="same_kind")
    B *= sw.astype(np.float32)[None, :]
    B.flat[:: len(sw) + 1] += 1.0
    factor, info = spotrf(B.T, lower=1, clean=0, overwrite_a=1)  # B.T: the same symmetric matrix, Fortran order
    if info != 0:
        raise np.linalg.LinAlgError(f"I + S K S is not positive definite (LAPACK spotrf info {info})")
    return factor, True


def dense_factor(B: np.ndarray) -> np.ndarray:
    """The lower Cholesky factor of B (float64) by the LAPACK call ``scipy.linalg.cho_factor(B, lower=True)``
    makes (dpotrf, same arguments, so the same bits), without its wrapper's checks and batching."""
    factor, info = dpotrf(B, lower=1, clean=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"B is not positive definite (LAPACK dpotrf info {info})")
    return factor


def dense_solve(factor: np.ndarray, right: np.ndarray) -> np.ndarray:
    """B^-1 right from ``dense_factor``'s factor: ``scipy.linalg.cho_solve``'s LAPACK call (dpotrs)."""
    solved, info = dpotrs(factor, right, lower=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"Cholesky solve failed (LAPACK dpotrs info {info})")
    return solved


def factor_solve(factor: np.ndarray, right: np.ndarray) -> np.ndarray:
    """B^-1 right from ``mode_factor``'s float32 lower factor (LAPACK spotrs), as float64."""
    solved, info = spotrs(factor, right, lower=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"Cholesky solve failed (LAPACK spotrs info {info})")
    return solved.astype(float)


def triangular_solve(factor: np.ndarray, right: np.ndarray, lower: bool, trans: int) -> np.ndarray:
    """``scipy.linalg.solve_triangular(factor, right, lower, trans)`` for a float32 factor: the same LAPACK call
    (strtrs, on the factor or on its transpose, as scipy picks by memory order), without the wrapper's checks."""
    if factor.flags.f_contiguous:
        solved, info = strtrs(factor, right, lower=lower, trans=trans)
    else:
        solved, info = strtrs(factor.T, right, lower=not lower, trans=1 - trans)
    if info != 0:
        raise np.linalg.LinAlgError(f"triangular solve failed (LAPACK strtrs info {info})")
    return solved


def sigmoid(z: np.ndarray) -> np.ndarray:
    """The logistic function 1 / (1 + exp(-z)), written with tanh so it never overflows."""
    return 0.5 * (1.0 + np.tanh(0.5 * z))
