"""Value of information in the robot's own currency: expected objects right, and the price of asking now.

For a learning state, the objects it will be judged on are estimated by the *judged rows*: the current
scene's objects, then a pool of unlabelled objects from scenes seen before. With P = p(y|x) the concept
models' posterior predictive (normalised over the concepts) and P' what it becomes after a simulated
answer, the value of that answer is what the robot's predictions gain when judged by P' (the standard
value of information: the better decision after the answer against the decision already made):

    "error":  sum_i P'[i, argmax P'_i] - P'[i, argmax P_i]   (expected objects right that change), or
    "log":    sum_i KL(P'_i || P_i)                         (expected log loss saved on the judged rows),

both >= 0 (``error-after``, Roy & McCallum's sum_i max P'_i - max P_i, was tried too; docs/strategies.md);
"error" is exactly 0 when no answer would change any prediction (nothing is uncertain enough
to matter). The gain of a question is its answers' values weighted as DT weighs them
(``learning.decision.candidates``): a label of object x by p(y|x), a demonstration of y by p(x|y) over
the scene, the feature question's answers F_{y,c} 1/|Y| each. P' comes from the fast what-if engine run on
the scene and the pool at once (``learning.whatif.fast.pair_table``, ``feature_outcomes`` with ``extra``):
one-site Laplace updates and batched refits, nothing refit per answer.

**The price** (one rule, nothing tuned). Let c be the cheapest question's cost, n = floor(B / c) the
questions the remaining budget B still buys and T the turns left, this one included. If n >= T the budget
cannot all be spent: asking now displaces nothing, the price is 0. Else only n of the T turns can have a
question, and a unit of budget spent now is a unit a later turn would have used: with the n questions
spread over the T turns, the unit saved goes to a later turn that would otherwise stay quiet with
probability 1 - n/T, where it buys the best question then, estimated by the best label question over the
judged rows now (gain per cost unit g*). So one cost unit is worth lambda = (1 - n/T) g* and a question
of cost k costs k lambda. The robot asks the question with the largest gain - price when that is positive.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from learning.actions import Action, DemoQuery, LabelQuery
from learning.decision.candidates import _normalised, candidate_actions
from learning.decision.features import label_distribution
from learning.whatif.base import cached
from learning.whatif.fast import feature_outcomes, pair_table

LOSSES = ("error", "log", "error-after")


def answer_value(P: np.ndarray, after: np.ndarray, loss: str) -> np.ndarray:
    """The value of each simulated answer (module docstring) over the last two axes (objects, concepts) of
    ``after``, against the current ``P`` (objects, concepts): shape after.shape[:-2]."""
    now, later = label_distribution(P), label_distribution(after)
    if loss == "error":
        decided = np.argmax(now, axis=-1)  # the predictions already made
        kept = np.take_along_axis(later, np.broadcast_to(decided[:, None], later.shape[:-1] + (1,)), axis=-1)[..., 0]
        return (later.max(axis=-1) - kept).sum(axis=-1)
    if loss == "error-after":  # Roy & McCallum's expected error reduction: sum_i max P'_i - max P_i (may be < 0)
        return later.max(axis=-1).sum(axis=-1) - now.max(axis=-1).sum()
    if loss == "log":
        ratio = np.log(np.maximum(later, 1e-300)) - np.log(np.maximum(now, 1e-300))
        return np.maximum(np.sum(np.where(later > 0, later * ratio, 0.0), axis=(-2, -1)), 0.0)
    raise ValueError(f"unknown loss '{loss}'; choose one of: {', '.join(LOSSES)}")


@dataclass(frozen=True)
class Price:
    """What one cost unit spent now is worth later (module docstring): lambda = (1 - n/T) g*."""

    questions_left: int  # n: the cheapest questions the remaining budget buys
    turns_left: int  # T: the turns left, this one included
    best_later: float  # g*: the best label question's gain per cost unit over the judged rows
    per_unit: float  # lambda

    def of(self, cost: float) -> float:
        return cost * self.per_unit


def price_rule(remaining_budget: float, cheapest_cost: float, turns_left: int, best_later: float) -> Price:
    """The price of one cost unit now (module docstring): 0 when n >= T, else (1 - n/T) g*."""
    n = int(np.floor(remaining_budget / cheapest_cost + 1e-9)) if cheapest_cost > 0 else turns_left
    T = max(int(turns_left), 1)
    share = max(0.0, 1.0 - n / T)
    return Price(n, T, float(best_later), share * max(float(best_later), 0.0))


@dataclass(frozen=True)
class Gains:
    """One turn's candidate queries with their expected gains (in the chosen loss and in objects right)."""

    actions: tuple[Action, ...]  # the affordable queries, in candidate order (no NoQuery)
    gain: np.ndarray  # the expected value of the answer to each (module docstring), in the chosen loss
    objects_right: np.ndarray  # the same in expected objects right (the error loss), for the reason sentence
    judged: int  # how many rows the robot is judged on here (scene + pool)
    price: Price


def voi_gains(state, pool: np.ndarray | None, loss: str = "error") -> Gains:
    """The gain of every affordable query over the scene and ``pool`` (raw rows), and this turn's price."""
    queries = tuple(a for a in candidate_actions(state) if a.kind != "none")
    m = len(state.scene_X)
    pool = np.zeros((0, len(state.feature_names))) if pool is None else np.asarray(pool, dtype=float)
    rows = np.vstack([state.scene_X, pool]) if len(pool) else np.asarray(state.scene_X)
    judged = len(rows)
    cheapest = min(state.costs[k] for k in ("label", "demo", "feature"))
    turns_left = state.turns - state.turn
    if judged == 0 or not queries:
        return Gains(queries, np.zeros(len(queries)), np.zeros(len(queries)), judged,
                     price_rule(state.remaining_budget, cheapest, turns_left, 0.0))
    P = state.probabilities(rows)
    extra = pool if len(pool) else None
    # one model version, scene and pool give one table: a quiet turn reuses the last one (as DT's engine does)
    version = (state.version, state.scene_id, hashlib.sha1(np.ascontiguousarray(pool).tobytes()).hexdigest())
    table = cached(state, "voi.pairs", version, lambda: pair_table(state, extra))  # [j, y, i, c] over judged rows
    q = label_distribution(P)  # p(y | row j)
    label_cost = state.costs["label"]

    features = [cached(state, "voi.feature", version, lambda: feature_outcomes(state, extra))] \
        if queries[-1].kind == "feature" else []

    def gains_in(loss_name: str):
        pair_value = answer_value(P, table, loss_name)  # (judged, |Y|): the value of answer <row j, concept y>
        label_gain = np.einsum("jy,jy->j", q, pair_value)  # E over the label's answer, every row j
        gains = []
        for action in queries:
            if isinstance(action, LabelQuery):
                gains.append(label_gain[action.object_index])
            elif isinstance(action, DemoQuery):
                y = state.concepts.index(action.concept)
                gains.append(float(_normalised(P[:m, y]) @ pair_value[:m, y]))
            else:  # [y, i, c], answer y with probability 1/|Y|
                gains.append(float(answer_value(P, features[0], loss_name).mean()))
        return np.array(gains), label_gain.max() / label_cost

    gain, best_later = gains_in(loss)
    objects_right = gain if loss == "error" else gains_in("error")[0]
    return Gains(queries, gain, objects_right, judged,
                 price_rule(state.remaining_budget, cheapest, turns_left, best_later))

