"""dt-voi: ask the question whose expected gain in objects right beats its price, else stay quiet (issue 40).

Utility: the expected value of the answer in the robot's own currency, objects it will get right (``error``;
or ``log``: log loss saved, ``error-after``: Roy & McCallum's expected error reduction), over the objects it
will be judged on, estimated by the current scene and a pool of the unlabelled objects of scenes it has
seen (``learning.decision.voi``; the fast what-if engine simulates every answer). A question that cannot
change any prediction is worth 0.

Price: one cost unit is worth lambda = (1 - n/T) g*, n the cheapest questions the budget
still buys, T the turns left, g* the best label question's gain per cost unit over the judged rows
(0 while n >= T: the budget cannot all be spent, asking displaces nothing). It asks the query with the
largest gain - cost x lambda when that is positive, so it stays quiet when nothing is uncertain (no gain)
or when the budget is short and this scene offers less than the pool (docs/strategies.md, "dt-voi").

The loss and the pool are read from learning/strategies/data/dt-voi.toml (chosen on the synthetic task,
docs/strategies.md). The pool is remembered within an episode: rows of earlier scenes of the same
state, most recent first, the training set's rows left out.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from learning.actions import Action, Decision, NoQuery
from learning.datafiles import check_keys, integer, read_toml, section, text
from learning.decision.resolution import EU_RESOLUTION, first_of_best
from learning.decision.voi import LOSSES, Gains, voi_gains
from learning.state import LearningState
from learning.strategies.base import Strategy

SETTINGS_FILE = Path(__file__).parent / "data" / "dt-voi.toml"
POOLS = ("scene", "seen")


@dataclass(frozen=True)
class VoiSettings:
    """dt-voi's choices (the data file says why): which loss, which pool, how many pool rows at most."""

    loss: str = "error"
    pool: str = "seen"
    pool_limit: int = 200

    @classmethod
    def load(cls, path: str | Path = SETTINGS_FILE) -> VoiSettings:
        path = Path(path)
        where = str(path)
        table = section(read_toml(path, "dt-voi settings"), "voi", where)
        check_keys(table, f"{where} [voi]", required=("loss", "pool", "pool_limit"))
        return cls(text(table, "loss", where, choices=LOSSES), text(table, "pool", where, choices=POOLS),
                   integer(table, "pool_limit", where, low=0))


class ValueOfInformationStrategy(Strategy):
    """dt-voi (module docstring); ``loss``, ``pool`` and ``pool_limit`` override the data file's."""

    def __init__(self, name: str = "dt-voi", loss: str | None = None, pool: str | None = None,
                 pool_limit: int | None = None, settings: str | Path = SETTINGS_FILE):
        chosen = VoiSettings.load(settings)
        self.name = name
        self.loss = loss or chosen.loss
        self.pool = pool or chosen.pool
        self.pool_limit = chosen.pool_limit if pool_limit is None else int(pool_limit)
        if self.loss not in LOSSES or self.pool not in POOLS or self.pool_limit < 0:
            raise ValueError(f"dt-voi takes loss in {LOSSES}, pool in {POOLS} and pool_limit >= 0, got "
                             f"{self.loss!r}, {self.pool!r}, {self.pool_limit!r}")
        self._owner: weakref.ref | None = None  # the state whose scenes ``_scenes`` holds (one episode)
        self._scenes: dict[int, np.ndarray] = {}
        self.last_gains: Gains | None = None

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        gains = voi_gains(state, self._pool(state), self.loss)
        self.last_gains = gains
        if not gains.actions:
            return self.nothing_affordable(state)
        net = gains.gain - np.array([gains.price.of(state.cost(a)) for a in gains.actions])
        best = first_of_best(net, EU_RESOLUTION * max(1.0, float(np.abs(gains.gain).max())))
        action = gains.actions[best]
        if net[best] <= EU_RESOLUTION * max(1.0, abs(float(gains.gain[best]))):
            return Decision(NoQuery(), _quiet_reason(state, action, gains, best))
        return Decision(action, _ask_reason(state, action, gains, best))

    def _pool(self, state: LearningState) -> np.ndarray | None:
        """Unlabelled rows of the earlier scenes of this episode (``pool`` "seen"), most recent first."""
        if self._owner is None or self._owner() is not state:
            self._owner, self._scenes = weakref.ref(state), {}
        if state.scene_id not in self._scenes:
            self._scenes[state.scene_id] = np.array(state.scene_X)
        if self.pool == "scene" or self.pool_limit == 0:
            return None
        X, _ = state.training_matrix()
        taught = {row.tobytes() for row in np.asarray(X, dtype=float)}
        rows = [row for scene_id in reversed(self._scenes) if scene_id != state.scene_id
                for row in self._scenes[scene_id] if row.tobytes() not in taught]
        return np.array(rows[: self.pool_limit]) if rows else None


def _question(action: Action) -> str:
    if action.kind == "label":
        return f"what object {action.object_index + 1} is"
    if action.kind == "demo":
        return f"for a demonstration of {action.concept}"
    return "which features matter"


def _objects(gains: Gains, index: int) -> str:
    expected = float(gains.objects_right[index])
    amount = f"{expected:.0f}" if expected >= 1.5 else f"{expected:.1f}"
    return f"about {amount} more of the {gains.judged} objects I have seen right"


def _price_words(gains: Gains, state: LearningState, action: Action) -> str:
    price = gains.price
    n, turns = price.questions_left, price.turns_left
    fit = f"{n} more question{'s fit' if n != 1 else ' fits'} the budget"
    if price.per_unit == 0.0:
        return f"nothing now: {fit} and {turns} turn{'s are' if turns != 1 else ' is'} left, so asking uses none up"
    return (f"{price.of(state.cost(action)):.2f} objects, what that budget should buy later: {fit} in {turns} "
            f"turns")


def _ask_reason(state: LearningState, action: Action, gains: Gains, index: int) -> str:
    return (f"I ask {_question(action)}: I expect to get {_objects(gains, index)}, more than the question's price "
            f"({_price_words(gains, state, action)}).")


def _quiet_reason(state: LearningState, action: Action, gains: Gains, index: int) -> str:
    if float(gains.objects_right[index]) < 0.05 and gains.price.per_unit == 0.0:
        return (f"Nothing to ask: I am sure enough of what I see; the best question, {_question(action)}, would "
                f"get {_objects(gains, index)}.")
    return (f"Nothing to ask: the best question, {_question(action)}, would get {_objects(gains, index)}, not "
            f"worth its price ({_price_words(gains, state, action)}).")
