"""Maximum-entropy inverse RL for the decision-feature weights (thesis §7.3.2, eq. 7.5-7.7).

The expert picks one candidate action per turn. Under maximum entropy the
policy consistent with matching the expert's feature counts is

    P(a | s_t, w) = exp(w . Phi_t[a]) / sum_b exp(w . Phi_t[b])

and maximising the entropy (eq. 7.5) under feature matching (eq. 7.6) is
maximising the log-likelihood of the expert's choices. Its gradient is eq.
7.7 turn by turn: sum_t Phi_t[a_t] - E_{P(.|s_t,w)}[Phi_t]. Because the DT
learner is myopic (it maximises EU(a) = w . Phi_t[a] each turn, eq. 7.1) this
per-turn model is exact for it: no dynamics model is needed, only the
candidate features the learner saw. The log-likelihood is concave in w, so
L-BFGS reaches the optimum in a few dozen iterations; the thesis's cap of 100
iterations and "keep the weights that do best on a validation set" act as
early stopping. The trajectory-level variant that samples rollouts lives in
``learning.irl.rollouts``.

torch (float64, autograd) computes the objective and its gradient; scipy's
L-BFGS-B takes the steps (or a plain Adam, ``AdamAscent``). torch.optim is not
used: its first use imports torch._dynamo, which costs more than a whole fit.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import torch
import torch.nn.functional as F
from scipy.optimize import minimize
from threadpoolctl import threadpool_limits

from learning.decision.resolution import EU_RESOLUTION
from learning.decision.weights_file import DecisionWeights
from learning.irl.demonstrations import QuestioningEpisode, common_feature_names

OPTIMIZERS = ("lbfgs", "adam")
POLICIES = ("softmax", "gated")
SELECTION_CRITERIA = ("agreement", "log_likelihood")


@dataclass(frozen=True)
class IrlConfig:
    """Fitting choices; the defaults are the ones the docs measure."""

    max_iterations: int = 100  # thesis §7.4.1
    l2: float = 1e-5  # penalty (l2/2)|v|^2 on the standardised weights v, per turn
    optimizer: str = "lbfgs"  # "lbfgs" (scipy L-BFGS-B on the torch objective) or "adam" (full batch)
    learning_rate: float = 0.05  # Adam only; L-BFGS uses step 1 and its line search
    standardize: bool = True  # fit on features divided by their spread between candidates
    tolerance: float = 1e-9  # stop when the loss changes by less than this (relative) or the gradient vanishes
    seed: int = 0
    threads: int = 1  # torch and BLAS threads during the fit; the arrays are tiny, more threads only contend
    select_by: str = "agreement"  # keep the iterate best on validation by "agreement" or "log_likelihood"
    policy: str = "softmax"  # "softmax" over all candidates, or "gated": ask-or-not, then which query (see below)
    signs: tuple[tuple[str, int], ...] = ()  # (feature, +1 | -1): that weight is kept >= 0 | <= 0 (issue 39)

    def __post_init__(self) -> None:
        if isinstance(self.max_iterations, bool) or not isinstance(self.max_iterations, int) \
                or self.max_iterations < 1:
            raise ValueError(f"max_iterations must be an integer >= 1, got {self.max_iterations!r}")
        if self.optimizer not in OPTIMIZERS:
            raise ValueError(f"unknown optimizer {self.optimizer!r}; accepted: {', '.join(OPTIMIZERS)}")
        for name in ("l2", "learning_rate", "tolerance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value) or value < 0:
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if isinstance(self.threads, bool) or not isinstance(self.threads, int) or self.threads < 1:
            raise ValueError(f"threads must be an integer >= 1, got {self.threads!r}")
        if self.policy not in POLICIES:
            raise ValueError(f"unknown policy {self.policy!r}; accepted: {', '.join(POLICIES)}")
        if self.select_by not in SELECTION_CRITERIA:
            raise ValueError(f"unknown select_by {self.select_by!r}; accepted: {', '.join(SELECTION_CRITERIA)}")
        if self.optimizer == "adam" and self.learning_rate <= 0:
            raise ValueError("learning_rate must be > 0 for the adam optimizer")
        for entry in self.signs:
            if not (isinstance(entry, tuple) and len(entry) == 2 and isinstance(entry[0], str)
                    and entry[1] in (1, -1) and not isinstance(entry[1], bool)):
                raise ValueError(f"signs must be (feature name, +1 or -1) pairs, got {entry!r}")

    def bounds(self, names: Sequence[str]) -> list[tuple[float | None, float | None]]:
        """L-BFGS-B bounds per feature from ``signs`` (the standardised weights share the raw ones' signs)."""
        signs = dict(self.signs)
        unknown = sorted(set(signs) - set(names))
        if unknown:
            raise ValueError(f"signs name {', '.join(unknown)}, which the demonstrations do not record; they record "
                             f"{', '.join(names)}")
        return [(0.0, None) if signs.get(n) == 1 else (None, 0.0) if signs.get(n) == -1 else (None, None)
                for n in names]


class PaddedTurns:
    """The turns with a real choice (>= 2 candidates) as one padded array (turns x max_actions x k)."""

    def __init__(self, episodes: Sequence[QuestioningEpisode], what: str = "episodes"):
        self.feature_names = common_feature_names(episodes, what)
        turns = [turn for episode in episodes for turn in episode.turns if turn.n_actions >= 2]
        if not turns:
            raise ValueError(f"{what}: no turn offers a choice (every turn has a single candidate action)")
        width = max(turn.n_actions for turn in turns)
        self.phi = np.zeros((len(turns), width, len(self.feature_names)))
        self.valid = np.zeros((len(turns), width), dtype=bool)
        self.chosen = np.array([turn.chosen for turn in turns], dtype=np.int64)
        self.no_query = np.full(len(turns), -1, dtype=np.int64)
        for i, turn in enumerate(turns):
            self.phi[i, :turn.n_actions] = turn.phi
            self.valid[i, :turn.n_actions] = True
            if turn.no_query_index is not None:
                self.no_query[i] = turn.no_query_index

    def __len__(self) -> int:
        return len(self.chosen)

    def choices(self, weights: np.ndarray, rtol: float = EU_RESOLUTION) -> np.ndarray:
        """argmax_a w . Phi[a] per turn; ties go to no query, else to the first (``irl_policy.greedy_choice``)."""
        utilities = np.where(self.valid, self.phi @ np.asarray(weights, dtype=np.float64), -np.inf)
        best = utilities.max(axis=1, keepdims=True)
        tied = utilities >= best - rtol * np.maximum(1.0, np.abs(best))
        rows = np.arange(len(self))
        nq_tied = (self.no_query >= 0) & tied[rows, np.maximum(self.no_query, 0)]
        return np.where(nq_tied, self.no_query, np.argmax(tied, axis=1))

    def agreement(self, weights: np.ndarray) -> float:
        """Fraction of turns on which the greedy DT choice is the expert's."""
        return float(np.mean(self.choices(weights) == self.chosen))

    def spread(self) -> np.ndarray:
        """Per feature, the RMS deviation of a candidate's value from its turn's mean: what the choice can see."""
        counts = self.valid.sum(axis=1, keepdims=True)
        means = (self.phi * self.valid[..., None]).sum(axis=1) / counts
        deviations = (self.phi - means[:, None, :]) * self.valid[..., None]
        return np.sqrt((deviations ** 2).sum(axis=(0, 1)) / self.valid.sum())


class _TorchTurns:
    """PaddedTurns as float64 tensors, with the log-likelihood of eq. 7.5-7.7 (softmax) or its gated form.

    The gated policy follows the DT's own two-step rule (thesis §6.4, §7.3.1: take the best query a* only
    if EU(a*) > U(s)). Whether to ask is a logistic choice between no query and a smooth maximum of the
    query utilities, their log-mean-exp, which unlike the softmax's log-sum-exp does not grow with the
    number of near-identical label queries; which query is then the softmax over the queries:

        P(ask) = sigmoid(LME_q(w . Phi[q]) - w . Phi[NQ]),   P(q | ask) = softmax_q(w . Phi[q]).

    With a dozen label queries that look alike, the plain softmax can explain an expert who asks on half
    the turns only by making each single query less attractive than silence, so the greedy DT never asks.
    Turns without a no-query candidate use the softmax.
    """

    def __init__(self, turns: PaddedTurns, scale: np.ndarray, identifiable: np.ndarray | None = None,
                 policy: str = "softmax"):
        keep = np.ones_like(scale) if identifiable is None else identifiable.astype(np.float64)
        self.phi = torch.from_numpy(turns.phi * (keep / scale))  # an unidentifiable column gets no gradient
        self.pad = torch.from_numpy(~turns.valid)
        self.chosen = torch.from_numpy(turns.chosen)
        self.policy = policy
        rows = np.arange(len(turns))
        has_nq = turns.no_query >= 0
        query = turns.valid.copy()
        query[rows[has_nq], turns.no_query[has_nq]] = False
        self.gated = torch.from_numpy(has_nq & (query.sum(axis=1) > 0))
        self.no_query = torch.from_numpy(np.maximum(turns.no_query, 0))
        self.not_query = torch.from_numpy(~query)
        self.log_queries = torch.from_numpy(np.log(np.maximum(query.sum(axis=1), 1)).astype(np.float64))
        self.quiet = torch.from_numpy(turns.chosen == turns.no_query)

    def mean_log_likelihood(self, v: torch.Tensor) -> torch.Tensor:
        """Softmax: (1/N) sum_t [v . Phi_t[a_t] - log sum_b exp(v . Phi_t[b])]; gated: see the class."""
        utilities = (self.phi @ v).masked_fill(self.pad, -torch.inf)
        chosen = utilities.gather(1, self.chosen[:, None])[:, 0]
        softmax = chosen - torch.logsumexp(utilities, dim=1)
        if self.policy == "softmax":
            return softmax.mean()
        queries = torch.logsumexp(utilities.masked_fill(self.not_query, -torch.inf), dim=1)
        ask = queries - self.log_queries - utilities.gather(1, self.no_query[:, None])[:, 0]
        ask = torch.where(self.gated, ask, torch.zeros_like(ask))  # keep the unused branch finite
        gated = torch.where(self.quiet, F.logsigmoid(-ask), F.logsigmoid(ask) + chosen - queries)
        return torch.where(self.gated, gated, softmax).mean()


class AdamAscent:
    """Adam (Kingma & Ba 2015) as plain arithmetic, ascending a given gradient; no torch.optim import needed."""

    def __init__(self, learning_rate: float, beta1: float = 0.9, beta2: float = 0.999, epsilon: float = 1e-8):
        self.learning_rate, self.beta1, self.beta2, self.epsilon = learning_rate, beta1, beta2, epsilon
        self.steps = 0
        self.mean: np.ndarray | None = None
        self.square: np.ndarray | None = None

    def step(self, x: np.ndarray, ascent: np.ndarray) -> np.ndarray:
        """The next iterate, moving x along the (bias-corrected, per-coordinate scaled) direction ``ascent``."""
        if self.mean is None or self.square is None:
            self.mean, self.square = np.zeros_like(x), np.zeros_like(x)
        self.steps += 1
        self.mean = self.beta1 * self.mean + (1 - self.beta1) * ascent
        self.square = self.beta2 * self.square + (1 - self.beta2) * ascent ** 2
        mean = self.mean / (1 - self.beta1 ** self.steps)
        square = self.square / (1 - self.beta2 ** self.steps)
        return x + self.learning_rate * mean / (np.sqrt(square) + self.epsilon)


@dataclass(frozen=True)
class IterationRecord:
    """One iteration (0 = the start) and both agreements. ``loss`` is the training objective of the
    per-turn fit, or the norm of the feature-count gap (eq. 7.7) in feature matching, where
    ``evaluation`` is the iterate's held-out score when it was evaluated (else None)."""

    iteration: int
    loss: float
    train_agreement: float
    validation_agreement: float | None
    evaluation: float | None = None


@dataclass(frozen=True, eq=False)
class IrlResult:
    """The selected weights and how the fit went."""

    weights: DecisionWeights
    iterations: int  # optimiser iterations run (<= max_iterations)
    best_iteration: int  # the iteration whose weights were kept (0 = the initial weights)
    seconds: float
    converged: bool  # the optimiser met its tolerance (always False for stochastic feature matching)
    train_agreement: float
    validation_agreement: float | None
    train_log_likelihood: float  # mean per turn, at the kept weights
    validation_log_likelihood: float | None
    train_turns: int
    validation_turns: int
    unidentified_features: tuple[str, ...]  # equal on every candidate of every turn: weight stays at its start
    history: tuple[IterationRecord, ...] = field(repr=False, default=())

    def summary(self) -> dict:
        """The JSON line of ``teachbot learn-weights``."""
        return {"iterations": self.iterations, "seconds": round(self.seconds, 4),
                "weights": self.weights.as_dict(), "validation_agreement": self.validation_agreement}


def feature_scale(turns: PaddedTurns, standardize: bool) -> tuple[np.ndarray, np.ndarray]:
    """Divisor per feature (its spread between candidates) and which features the choices can identify at all."""
    spread = turns.spread()
    identifiable = spread > 1e-12
    if not standardize:
        return np.ones_like(spread), identifiable
    return np.where(identifiable, spread, 1.0), identifiable


def fit_maxent_irl(train: Sequence[QuestioningEpisode], validation: Sequence[QuestioningEpisode] | None = None,
                   config: IrlConfig | None = None, initial_weights: np.ndarray | None = None) -> IrlResult:
    """Learn w from expert episodes by per-turn maximum-entropy IRL (thesis eq. 7.5-7.7).

    Every iteration is scored; the kept weights are those with the best
    validation agreement (ties: higher validation log-likelihood, then the
    earlier iteration), or with ``select_by="log_likelihood"`` the other way
    round. Without validation episodes the training set scores (its
    log-likelihood includes the L2 penalty).
    """
    config = config or IrlConfig()
    with compute_threads(config.threads):
        return _fit_per_turn(train, validation, config, initial_weights)


@contextmanager
def compute_threads(n: int):
    """Run a block with ``n`` torch and BLAS threads, then restore the caller's settings.

    The arrays are tiny: on a busy machine extra threads only spin-wait (OpenBLAS
    inside scipy's L-BFGS-B made a fit six times slower here).
    """
    previous = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        with threadpool_limits(limits=n):
            yield
    finally:
        torch.set_num_threads(previous)


def _fit_per_turn(train, validation, config: IrlConfig, initial_weights) -> IrlResult:
    started = time.perf_counter()
    torch.manual_seed(config.seed)
    train_turns = PaddedTurns(train, "training episodes")
    names = train_turns.feature_names
    validation_turns = None
    if validation:
        validation_turns = PaddedTurns(validation, "validation episodes")
        if validation_turns.feature_names != names:
            raise ValueError(f"validation episodes have features {list(validation_turns.feature_names)}, training "
                             f"episodes {list(names)}; they must match")
    scale, identifiable = feature_scale(train_turns, config.standardize)
    w0 = np.zeros(len(names)) if initial_weights is None else np.asarray(initial_weights, dtype=np.float64)
    if w0.shape != (len(names),) or not np.all(np.isfinite(w0)):
        raise ValueError(f"initial_weights must be {len(names)} finite numbers, got shape {w0.shape}")
    bounds = config.bounds(names)
    w0 = project(w0, bounds)  # a start outside the signs begins at the nearest weights inside them
    data = _TorchTurns(train_turns, scale, identifiable, config.policy)
    held_out = _TorchTurns(validation_turns, scale, policy=config.policy) if validation_turns is not None else None
    penalised = identifiable.astype(np.float64)

    def value_and_gradient(x: np.ndarray) -> tuple[float, np.ndarray]:
        """Negative mean log-likelihood + (l2/2)|v|^2 and its autograd gradient, at standardised weights x."""
        v = torch.tensor(x, dtype=torch.float64, requires_grad=True)
        loss = -data.mean_log_likelihood(v) + 0.5 * config.l2 * (torch.from_numpy(penalised) * v * v).sum()
        (gradient,) = torch.autograd.grad(loss, v)
        return float(loss.detach()), gradient.numpy().copy()

    history: list[IterationRecord] = []
    best: dict = {}

    def score(x: np.ndarray) -> None:
        """Record one iterate and keep it if it is the best so far on validation (ties: log-likelihood)."""
        w, loss = x / scale, value_and_gradient(x)[0]
        record = IterationRecord(len(history), loss, train_turns.agreement(w),
                                 validation_turns.agreement(w) if validation_turns is not None else None)
        history.append(record)
        key: tuple[float | None, float | None]  # validation agreement is None only without held-out turns
        if held_out is not None:
            with torch.no_grad():
                key = (record.validation_agreement, float(held_out.mean_log_likelihood(torch.from_numpy(x))))
        else:
            key = (record.train_agreement, -loss)
        if config.select_by == "log_likelihood":
            key = key[::-1]
        if not best or key > best["key"]:
            best.update(key=key, w=w.copy(), iteration=record.iteration)

    x0 = w0 * scale
    score(x0)
    if config.optimizer == "lbfgs":
        outcome = minimize(value_and_gradient, x0, jac=True, method="L-BFGS-B", callback=score, bounds=bounds,
                           options={"maxiter": config.max_iterations, "maxcor": 20, "ftol": config.tolerance,
                                    "gtol": config.tolerance})
        iterations, converged = len(history) - 1, bool(outcome.success)
    else:
        adam, x, converged = AdamAscent(config.learning_rate), x0.copy(), False
        for _ in range(config.max_iterations):
            loss, gradient = value_and_gradient(x)
            x = project(adam.step(x, -gradient), bounds)
            score(x)
            if np.abs(gradient).max() <= config.tolerance:
                converged = True
                break
        iterations = len(history) - 1
    best_w, best_iteration = best["w"], best["iteration"]
    settings = {"method": "maxent-irl-per-turn", "policy": config.policy, "optimizer": config.optimizer,
                "l2": float(config.l2), "select_by": config.select_by}
    if config.signs:
        settings["signs"] = ", ".join(f"{n} {'>=' if sign > 0 else '<='} 0" for n, sign in config.signs)
    return make_result(names, best_w, identifiable, history, best_iteration, iterations, converged, settings,
                       train_turns, validation_turns, started)


def project(w: np.ndarray, bounds: Sequence[tuple[float | None, float | None]]) -> np.ndarray:
    """w clipped into the sign bounds (a weight on the wrong side becomes 0)."""
    low = np.array([-np.inf if lo is None else lo for lo, _ in bounds])
    high = np.array([np.inf if hi is None else hi for _, hi in bounds])
    return np.clip(w, low, high)


def make_result(names: tuple[str, ...], w: np.ndarray, identifiable: np.ndarray,
                history: Sequence[IterationRecord], best_iteration: int, iterations: int, converged: bool,
                settings: dict, train_turns: PaddedTurns, validation_turns: PaddedTurns | None,
                started: float) -> IrlResult:
    """Package kept weights, scores and provenance (``settings`` first) into an IrlResult."""
    train_ll = log_likelihood(train_turns, w)
    validation_ll = log_likelihood(validation_turns, w) if validation_turns is not None else None
    kept = history[best_iteration]
    provenance = {**settings, "iterations": iterations, "best_iteration": best_iteration,
                  "train_turns": len(train_turns), "train_agreement": round(kept.train_agreement, 6)}
    if validation_turns is not None:
        assert kept.validation_agreement is not None, "every record has it when there are validation turns"
        provenance.update(validation_turns=len(validation_turns),
                          validation_agreement=round(kept.validation_agreement, 6))
    return IrlResult(
        weights=DecisionWeights(names, w, provenance), iterations=iterations, best_iteration=best_iteration,
        seconds=time.perf_counter() - started, converged=converged, train_agreement=kept.train_agreement,
        validation_agreement=kept.validation_agreement, train_log_likelihood=train_ll,
        validation_log_likelihood=validation_ll, train_turns=len(train_turns),
        validation_turns=len(validation_turns) if validation_turns is not None else 0,
        unidentified_features=tuple(n for n, ok in zip(names, identifiable) if not ok), history=tuple(history))


def log_likelihood(turns: PaddedTurns, w: np.ndarray) -> float:
    """Mean per-turn log P(a_t | s_t, w) of the expert's choices under the MaxEnt policy."""
    weights = torch.from_numpy(np.array(w, dtype=np.float64))  # a copy: the caller's may be read-only
    with torch.no_grad():
        return float(_TorchTurns(turns, np.ones(turns.phi.shape[2])).mean_log_likelihood(weights))


def feature_count_gap(turns: PaddedTurns, weights: np.ndarray) -> np.ndarray:
    """Eq. 7.7 per turn, averaged: mean_t (Phi_t[a_t] - E_{P(.|s_t,w)}[Phi_t]); zero at the MaxEnt optimum."""
    utilities = np.where(turns.valid, turns.phi @ np.asarray(weights, dtype=np.float64), -np.inf)
    policy = np.exp(utilities - utilities.max(axis=1, keepdims=True))
    policy /= policy.sum(axis=1, keepdims=True)
    expected = np.einsum("ta,tak->tk", policy, turns.phi)
    chosen = turns.phi[np.arange(len(turns)), turns.chosen]
    return (chosen - expected).mean(axis=0)


def split_episodes(episodes: Sequence[QuestioningEpisode], n_validation: int,
                   rng: np.random.Generator) -> tuple[list[QuestioningEpisode], list[QuestioningEpisode]]:
    """Hold out ``n_validation`` whole episodes, chosen by ``rng``; returns (train, validation) in input order."""
    episodes = list(episodes)
    if not 0 <= n_validation < len(episodes):
        raise ValueError(f"n_validation must be in 0..{len(episodes) - 1} for {len(episodes)} episodes "
                         f"(at least one episode must remain for training), got {n_validation}")
    held = set(rng.choice(len(episodes), size=n_validation, replace=False).tolist()) if n_validation else set()
    return ([e for i, e in enumerate(episodes) if i not in held], [e for i, e in enumerate(episodes) if i in held])


__all__ = ["AdamAscent", "IrlConfig", "IrlResult", "IterationRecord", "PaddedTurns", "compute_threads",
           "feature_count_gap", "feature_scale", "fit_maxent_irl", "log_likelihood", "make_result", "split_episodes"]
