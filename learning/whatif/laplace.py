"""Laplace-GP arithmetic for the fast what-if engine (Rasmussen & Williams ch. 3; thesis eq. 6.3).

Two pieces:

* ``scene_posterior`` and ``one_site_probabilities``: the joint Laplace
  posterior N(mu, Sigma) of the latent function at the scene objects, and
  what it becomes when one scene object j joins the training set with label
  t in {+1, -1}. The existing training sites are kept as the Gaussians of the
  current Laplace fit; the new logistic site is fitted exactly (1-D Newton on
  log N(f; mu_j, Sigma_jj) + log sigma(t f)), which is a rank-one update:

      mu'   = mu + Sigma[:, j] (f*_j - mu_j) / Sigma_jj
      var'  = diag(Sigma) - Sigma[:, j]^2 w / (1 + w Sigma_jj),  w = sigma(f*)(1 - sigma(f*))

  The approximation is that the old sites do not move: a full refit would
  re-linearise them at the new mode (a second-order effect).
* ``fit_modes``: R&W algorithm 3.1 for several label vectors sharing one
  kernel matrix, with the Cholesky factors in float32 (B = I + W^1/2 K W^1/2
  has eigenvalues >= 1, so single precision costs ~1e-6 in the latent mode).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import spotrf, spotrs

from learning.gp import BinaryGPClassifier, rbf_kernel, sigmoid, triangular_solve

MIN_VARIANCE = 1e-12
MIN_SITE_SCALE = 1e-6  # W^1/2 below this: too small to divide by


def probit_probability(mean: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """p(y = 1) ~ sigma(mu / sqrt(1 + pi var / 8)), as ``BinaryGPClassifier.predict_proba``."""
    return sigmoid(mean / np.sqrt(1.0 + np.pi * np.maximum(variance, MIN_VARIANCE) / 8.0))


def _probit_in_place(mean: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """``probit_probability(mean, variance)`` computed in the arrays given (both are overwritten): the same bits."""
    np.maximum(variance, MIN_VARIANCE, out=variance)
    variance *= np.pi
    variance /= 8.0
    variance += 1.0
    np.sqrt(variance, out=variance)
    np.divide(mean, variance, out=mean)
    mean *= 0.5  # sigmoid, as gp.sigmoid: 0.5 (1 + tanh(z / 2))
    np.tanh(mean, out=mean)
    mean += 1.0
    mean *= 0.5
    return mean


@dataclass(frozen=True)
class ScenePosterior:
    """The current Laplace posterior of one classifier, seen from the scene (R&W eq. 3.21, 3.24).

    mean (m,) and cov (m, m) of the latent function at the scene objects; and, if the classifier has
    training data, cross (n, m) = Cov(f_train, f_scene) with the mode and W at the training points.
    """

    mean: np.ndarray
    cov: np.ndarray
    cross: np.ndarray | None = None
    mode: np.ndarray | None = None
    W: np.ndarray | None = None


def scene_kernels(X: np.ndarray, scene: np.ndarray, length_scale: float, variance: float):
    """K(scene, scene) and K(train, scene)."""
    return rbf_kernel(scene, scene, length_scale, variance), rbf_kernel(X, scene, length_scale, variance)


def scene_posterior(model: BinaryGPClassifier, scene: np.ndarray, kernels: tuple | None = None) -> ScenePosterior:
    """The posterior of ``model`` at the rows ``scene``.

    With S = W^1/2 and B = I + S K S = L L^T: V = L^-1 S K_ns, Cov(scene) = K_ss - V^T V, and
    Cov(train, scene) = K_ns - K S B^-1 S K_ns = S^-1 B^-1 S K_ns (as S B^-1 S = (K + W^-1)^-1), which
    needs no K_nn; rows whose W is too small to divide by use the first form. ``kernels`` = (K_ss, K_ns)
    may be passed in when several classifiers share their training rows and features.
    """
    X = model.X_train_
    if kernels is None:
        kernels = scene_kernels(X, scene, model.length_scale_, model.variance)
    K_ss, K_ns = kernels
    if len(model.targets_) == 0:
        return ScenePosterior(np.zeros(len(scene)), K_ss)
    factor, lower = model.L_
    sw = model.W_sqrt_
    factor32 = np.asarray(factor, dtype=np.float32)  # the model's factor is float32 already (gp.mode_factor)
    V32 = triangular_solve(factor32, (sw[:, None] * K_ns).astype(np.float32), lower, 0)
    solved = triangular_solve(factor32, V32, lower, 1).astype(float)  # B^-1 S K_ns
    V = V32.astype(float)
    cross = solved / np.maximum(sw, MIN_SITE_SCALE)[:, None]
    tiny = np.flatnonzero(sw < MIN_SITE_SCALE)
    if len(tiny):
        K_tn = rbf_kernel(X[tiny], X, model.length_scale_, model.variance)
        cross[tiny] = K_ns[tiny] - K_tn @ (sw[:, None] * solved)
    return ScenePosterior(K_ns.T @ model.grad_, K_ss - V.T @ V, cross, model.f_hat_, sw * sw)


def stack_posteriors(posteriors: list[ScenePosterior]) -> ScenePosterior:
    """Several classifiers' posteriors over the same scene (and the same training rows) as one batch."""
    first = posteriors[0]

    def stacked(name: str):
        return None if getattr(first, name) is None else np.stack([getattr(p, name) for p in posteriors])

    return ScenePosterior(stacked("mean"), stacked("cov"), stacked("cross"), stacked("mode"), stacked("W"))


def one_site_probabilities(posterior: ScenePosterior, max_steps: int = 50, tolerance: float = 1e-10) -> np.ndarray:
    """p(y=1 | x_i) after adding scene object j with label t: array [t, j, i], t = 0 for +1 and 1 for -1.

    1. The rank-one update with the new site fitted exactly, the old sites kept as the Gaussians of the
       current fit (module docstring).
    2. One correction of the mean: the old sites' log-likelihood gradients, evaluated where step 1
       moved their latent values, differ from their Gaussian stand-ins by r_i = sigma(f_i) - sigma(f'_i)
       + W_i (f'_i - f_i) (second order in the move); a Newton step with the step-1 Hessian shifts the
       scene means by Cov'(scene, train) r, Cov' being the covariance after the new site (rank-one again).
    The variances keep the old sites' precisions W (a first-order correction for their move was tried:
    it halves the mean error but sometimes overshoots, doubling the largest one).

    A batch of classifiers (``stack_posteriors``: a leading axis g on every array) gives [g, t, j, i],
    all in one pass: no Python loop over the classifiers.
    """
    if posterior.mean.ndim == 1:
        return one_site_probabilities(stack_posteriors([posterior]), max_steps, tolerance)[0]
    mean, cov = posterior.mean, posterior.cov  # (g, m), (g, m, m)
    n_batch, m = mean.shape
    if m == 0:
        return np.zeros((n_batch, 2, 0, 0))
    diagonal = np.diagonal(cov, axis1=1, axis2=2)  # (g, m)
    site_variance = np.maximum(diagonal, MIN_VARIANCE)[:, None, :]  # (g, 1, m)
    targets = np.array([1.0, -1.0])[None, :, None]
    mean_t = mean[:, None, :]
    f = np.broadcast_to(mean_t, (n_batch, 2, m)).copy()
    for _ in range(max_steps):  # maximise log N(f; mu_j, s_j) + log sigma(t f): concave, 1-D per (g, t, j)
        pi = sigmoid(f)
        gradient = -(f - mean_t) / site_variance + (targets + 1.0) / 2.0 - pi
        step = gradient / (1.0 / site_variance + pi * (1.0 - pi))
        f += step
        if np.max(np.abs(step), initial=0.0) < tolerance:
            break
    pi = sigmoid(f)
    w = pi * (1.0 - pi)
    shift = (f - mean_t) / site_variance  # (g, 2, m): mean update per unit of Sigma[:, j]
    shrink = w / (1.0 + w * site_variance)  # (g, 2, m)
    # The [g, t, j, i] arrays below are built in place (each the same operations in the same order as
    # mean + cov shift, along - cov (shrink at_site), diag - cov^2 shrink and probit_probability: the same bits)
    new_mean = np.multiply(cov[:, None, :, :], shift[..., None])  # [g, t, j, i]
    new_mean += mean[:, None, None, :]
    if posterior.cross is not None:
        assert posterior.mode is not None and posterior.W is not None, "cross, mode and W are set together"
        cross, mode, W = posterior.cross, posterior.mode[:, None, None, :], posterior.W[:, None, None, :]
        # residual = sigmoid(mode) - sigmoid(moved) + W (moved - mode), moved = mode + Cov(train, j) shift,
        # on [g, t, j, n] arrays (the largest of the decision) computed in place, the same operations in order
        moved = cross.transpose(0, 2, 1)[:, None, :, :] * shift[..., None]
        moved += mode  # [g, t, j, n]
        residual = np.multiply(moved, 0.5)
        np.tanh(residual, out=residual)
        residual += 1.0
        residual *= 0.5  # sigmoid(moved), as gp.sigmoid
        np.subtract(sigmoid(mode), residual, out=residual)
        moved -= mode
        moved *= W
        residual += moved
        # Cov(scene, train) r for every (g, t, j), one matrix product per classifier
        along = np.matmul(residual.reshape(n_batch, 2 * m, -1), cross).reshape(n_batch, 2, m, m)
        at_site = np.diagonal(along, axis1=2, axis2=3)  # (g, t, j), a view of along: read before along changes
        along -= np.multiply(cov[:, None, :, :], (shrink * at_site)[..., None])
        new_mean += along
    new_variance = np.multiply(np.square(cov)[:, None, :, :], shrink[..., None])
    np.subtract(diagonal[:, None, None, :], new_variance, out=new_variance)
    return _probit_in_place(new_mean, new_variance)


def _log_likelihood(targets: np.ndarray, f: np.ndarray) -> np.ndarray:
    """sum_i log sigma(t_i f_i) per row."""
    return -np.logaddexp(0.0, -targets * f).sum(axis=-1)


def _backtrack(x, step, f, f_step, psi, objective, halvings: int = 30):
    """Newton steps with backtracking per row: halve a row's step until its objective does not fall.

    ``x`` moves by ``step`` and the latent ``f`` by ``f_step`` (the same step seen through the kernel);
    ``objective(x, f)`` is the Laplace objective Psi per row. Returns the scales and the accepted
    (x, f, Psi).
    """
    scale = np.ones(len(x))
    for _ in range(halvings):
        trial_x, trial_f = x + scale[:, None] * step, f + scale[:, None] * f_step
        trial_psi = objective(trial_x, trial_f)
        worse = trial_psi < psi - 1e-12 * np.abs(psi)
        if not np.any(worse):
            break
        scale[worse] /= 2.0
    return scale, trial_x, trial_f, trial_psi


def fit_modes(kernels: np.ndarray, targets: np.ndarray, kernel_of_row: np.ndarray | None = None,
              start: np.ndarray | None = None, tolerance: float = 1e-5, max_steps: int = 100,
              refactor_above: float = 0.25, final_refactor_above: float = 1e-3):
    """Laplace modes for label rows ``targets`` (b, n) in {-1, +1} (R&W alg. 3.1), many problems at once.

    Row b uses kernel ``kernels[kernel_of_row[b]]`` ((s, n, n); a single (n, n) kernel serves every row).
    The first step is R&W's Newton step from the latent values ``start`` (b, n) (default 0), which also
    gives a with f = K a. Then Newton on a, the mode being where a = grad log p(y | f):
    a <- a + (I + W K)^-1 (grad - a), halving a step that lowers Psi = log p(y | f) - a.f / 2. The
    residual grad - a is float64; the solve uses a float32 Cholesky factor of B = I + W^1/2 K W^1/2,
    which costs accuracy only in the step, not in the fixed point. A row keeps its factor once its latent
    values move by less than ``refactor_above`` per step (chord steps: O(n^2) instead of O(n^3)) and stops
    once they move by less than ``tolerance``; its factor is refreshed at the end if the mode moved more
    than ``final_refactor_above`` since (the predictive variance needs W at the mode).

    Returns (W^1/2 (b, n), Cholesky factors (b, n, n) float32, gradients (b, n)) at the mode; each
    factor is stored transposed (``factors[b].T`` is the lower factor, Fortran-ordered for LAPACK).
    """
    kernels = np.asarray(kernels, dtype=float)
    if kernels.ndim == 2:
        kernels = kernels[None]
    n_rows, n = targets.shape
    kernel_of_row = np.zeros(n_rows, dtype=int) if kernel_of_row is None else np.asarray(kernel_of_row)
    kernels32 = kernels.astype(np.float32)
    positive = (targets + 1.0) / 2.0
    f = np.zeros((n_rows, n)) if start is None else np.array(start, dtype=float)
    sw = np.empty((n_rows, n))
    factors = np.empty((n_rows, n, n), dtype=np.float32)
    factored_at = np.empty((n_rows, n))

    def times_K(vectors: np.ndarray, rows: np.ndarray) -> np.ndarray:  # row b: K_b v_b, one GEMM per kernel
        result = np.empty_like(vectors)
        for k in np.unique(kernel_of_row[rows]):
            chosen = np.flatnonzero(kernel_of_row[rows] == k)
            result[chosen] = vectors[chosen] @ kernels[k]  # kernels are symmetric
        return result

    def factorise(rows) -> None:
        for row in rows:
            factored_at[row] = f[row]
            pi = sigmoid(f[row])
            sw[row] = np.sqrt(pi * (1.0 - pi))
            weights = sw[row].astype(np.float32)
            B = weights[:, None] * kernels32[kernel_of_row[row]]  # B = I + S K S, built in place (one n x n array)
            B *= weights[None, :]
            B.flat[:: n + 1] += 1.0
            # B is symmetric, so B.T is the same matrix in the Fortran order LAPACK wants (no copy);
            # the factor comes back in Fortran order and is stored transposed, again without a copy.
            factors[row] = spotrf(B.T, lower=1, clean=0, overwrite_a=1)[0].T

    def apply_inverse(vectors: np.ndarray, rows: np.ndarray) -> np.ndarray:  # (I + W K)^-1 v, per row
        right = (sw[rows] * times_K(vectors, rows)).astype(np.float32)
        solved = np.array([spotrs(factors[row].T, r, lower=1)[0] for row, r in zip(rows, right)])
        return vectors - sw[rows] * solved

    every = np.arange(n_rows)
    factorise(every)
    pi = sigmoid(f)
    a = apply_inverse(pi * (1.0 - pi) * f + positive - pi, every)  # R&W alg. 3.1, lines 4-8
    f_new = times_K(a, every)
    change = np.max(np.abs(f_new - f), axis=1, initial=0.0)
    f = f_new
    psi = _log_likelihood(targets, f) - 0.5 * np.einsum("bi,bi->b", a, f)
    for _ in range(max_steps):
        active = np.flatnonzero(change >= tolerance)
        if len(active) == 0:
            break
        factorise(active[change[active] > refactor_above])
        step = apply_inverse(positive[active] - sigmoid(f[active]) - a[active], active)
        f_step = times_K(step, active)
        _, trial_a, trial_f, trial_psi = _backtrack(  # rows whose objective fell (rare: far from the mode)
            a[active], step, f[active], f_step, psi[active],
            lambda x, f_x, t=targets[active]: _log_likelihood(t, f_x) - 0.5 * np.einsum("bi,bi->b", x, f_x))
        change[active] = np.max(np.abs(trial_f - f[active]), axis=1, initial=0.0)
        a[active], f[active], psi[active] = trial_a, trial_f, trial_psi
    factorise(np.flatnonzero(np.max(np.abs(f - factored_at), axis=1, initial=0.0) > final_refactor_above))
    return sw, factors, positive - sigmoid(f)


def predict_from_modes(cross_kernels: np.ndarray, variance: float, sw: np.ndarray, factors: np.ndarray,
                       gradient: np.ndarray, kernel_of_row: np.ndarray | None = None) -> np.ndarray:
    """p(y=1 | scene) (b, m) from ``fit_modes`` output and train-scene kernels (s, n, m) (R&W alg. 3.2)."""
    cross_kernels = np.asarray(cross_kernels, dtype=float)
    if cross_kernels.ndim == 2:
        cross_kernels = cross_kernels[None]
    kernel_of_row = np.zeros(len(sw), dtype=int) if kernel_of_row is None else np.asarray(kernel_of_row)
    K_ns = cross_kernels[kernel_of_row]
    mean = np.matmul(gradient[:, None, :], K_ns)[:, 0, :]
    right = sw.astype(np.float32)[:, :, None] * K_ns.astype(np.float32)
    V = np.array([triangular_solve(factor.T, r, lower=True, trans=0) for factor, r in zip(factors, right)])
    latent_variance = variance - np.einsum("bij,bij->bj", V, V, dtype=np.float64)
    return probit_probability(mean, latent_variance)


def pivoted_cholesky(points: np.ndarray, length_scale: float, variance: float, tolerance: float,
                     max_rank: int, truncate: bool = False) -> np.ndarray | None:
    """Phi (N, r) with K(points, points) ~ Phi Phi^T, every residual diagonal entry below ``tolerance``.

    Greedy pivoted Cholesky: each step takes the point with the largest residual variance. Returns None
    if ``max_rank`` columns do not reach the tolerance (the kernel is not of low numerical rank), or with
    ``truncate`` those ``max_rank`` columns (a rough approximation, e.g. to start Newton from).
    """
    n_points = len(points)
    if n_points == 0:
        return np.zeros((0, 0))
    residual = np.full(n_points, float(variance))
    width = min(max_rank, n_points)
    Phi_T = np.zeros((width, n_points))  # built row by row (contiguous), returned transposed
    scale = -0.5 / length_scale**2
    norms = np.einsum("ij,ij->i", points, points)
    for k in range(width + 1):
        pivot = int(residual.argmax())
        if residual[pivot] < tolerance:
            return Phi_T[:k].T
        if k == width:
            return Phi_T.T if truncate else None
        column = np.exp(scale * (norms + norms[pivot] - 2.0 * (points @ points[pivot])))  # k(x, x_pivot) / variance
        column *= variance
        column -= Phi_T[:k, pivot] @ Phi_T[:k]
        column /= np.sqrt(residual[pivot])
        Phi_T[k] = column
        residual -= column * column
    return None


def pad_columns(blocks: list[np.ndarray]) -> np.ndarray:
    """Stack (N, r_i) feature blocks into (s, N, max r_i) with zero columns: each Phi Phi^T is unchanged."""
    width = max(block.shape[1] for block in blocks)
    stacked = np.zeros((len(blocks), blocks[0].shape[0], width))
    for k, block in enumerate(blocks):
        stacked[k, :, : block.shape[1]] = block
    return stacked


def fit_weight_space(Phi: np.ndarray, targets: np.ndarray, tolerance: float = 1e-5, max_steps: int = 50):
    """Laplace fits with low-rank kernels K = Phi Phi^T: f = Phi z, z ~ N(0, I), for label rows (b, n).

    ``Phi`` is (n, r), shared by every row of ``targets`` (b, n), or (b, n, r), one per row (e.g. several
    subsets padded to one width by ``pad_columns``: a zero column keeps its weight at 0 and changes
    nothing). With K = Phi Phi^T the Laplace mode is a logistic regression on the features Phi with a
    unit Gaussian prior: Newton on z with Hessian C = I + Phi^T W Phi (r x r), O(n r^2) per step instead
    of O(n^3), halving a step that lowers Psi(z) = log p(y | Phi z) - |z|^2 / 2. The gradient is float64;
    the Hessian's product is float32 (it only shapes the step). A row stops once its latent values move
    by less than ``tolerance``. Returns z (b, r) and C (b, r, r), C from the last step (within tolerance).
    """
    n_rows, n = targets.shape
    shared = Phi.ndim == 2
    rank = Phi.shape[-1]
    Phi32 = Phi.astype(np.float32)
    positive = (targets + 1.0) / 2.0
    identity = np.eye(rank)
    z = np.zeros((n_rows, rank))
    C = np.empty((n_rows, rank, rank))
    f = np.zeros((n_rows, n))  # f_b = Phi_b z_b
    psi = _log_likelihood(targets, f)  # Psi at z = 0
    active = np.arange(n_rows)
    for _ in range(max_steps):
        pi = sigmoid(f[active])
        weights = (pi * (1.0 - pi)).astype(np.float32)[:, None, :]
        if shared:
            gradient = (positive[active] - pi) @ Phi - z[active]
            C[active] = identity + np.matmul(Phi32.T[None, :, :] * weights, Phi32)
        else:
            rows, rows32 = (Phi, Phi32) if len(active) == n_rows else (Phi[active], Phi32[active])
            gradient = np.matmul((positive[active] - pi)[:, None, :], rows)[:, 0, :] - z[active]
            C[active] = identity + np.matmul(rows32.transpose(0, 2, 1) * weights, rows32)
        step = np.linalg.solve(C[active], gradient[:, :, None])[:, :, 0]
        step_f = step @ Phi.T if shared else np.matmul(rows, step[:, :, None])[:, :, 0]
        scale, trial_z, trial_f, trial_psi = _backtrack(
            z[active], step, f[active], step_f, psi[active],
            lambda x, f_x, t=targets[active]: _log_likelihood(t, f_x) - 0.5 * np.einsum("br,br->b", x, x))
        moved = np.max(np.abs(scale[:, None] * step_f), axis=1, initial=0.0)
        z[active], f[active], psi[active] = trial_z, trial_f, trial_psi
        active = active[moved >= tolerance]
        if len(active) == 0:
            break
    return z, C


def predict_weight_space(Phi_scene: np.ndarray, variance: float, z: np.ndarray, C: np.ndarray) -> np.ndarray:
    """p(y=1 | scene) (b, m): mean phi*.z, variance phi*^T C^-1 phi* plus the residual k** - |phi*|^2.

    ``Phi_scene`` is (m, r), shared, or (b, m, r), one per row.
    """
    Phi_scene = np.broadcast_to(Phi_scene, (len(z),) + Phi_scene.shape[-2:])
    mean = np.matmul(Phi_scene, z[:, :, None])[:, :, 0]
    solved = np.linalg.solve(C, Phi_scene.transpose(0, 2, 1))  # (b, r, m)
    explained = np.einsum("bmr,brm->bm", Phi_scene, solved)
    residual = np.maximum(variance - np.einsum("bmr,bmr->bm", Phi_scene, Phi_scene), 0.0)
    return probit_probability(mean, explained + residual)
