"""The settings of one teaching episode, with their defaults written once.

``EpisodeSettings`` is shared by ``demo``, ``teach`` (``SessionSettings`` adds
the teacher), ``expert`` (``ExpertSettings``, the thesis's training condition)
and the regression suites (``EpisodeSpec.settings()``); the command-line
defaults are read from :data:`DEFAULTS`. Bad values are refused when the
settings are made, with a :class:`~learning.errors.SettingsError` naming the option.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Integral, Real

from dialog.user_weights import weights_from_record
from learning.actions import DEFAULT_COSTS
from learning.errors import SettingsError
from learning.limits import check_limit, check_questions
from learning.strategies import DEFAULT_STRATEGY, make_strategy

__all__ = ["DEFAULTS", "EpisodeSettings", "check_allocation", "check_costs"]


def check_allocation(turns, budget, change_every, realtime=None, seed=0, seconds=None) -> None:
    """T turns, budget B, a change every r turns, seconds per turn (None: turn-based), the seed and an embodied
    allocation in seconds (None: time in turns), or SettingsError; each within its limit (learning/limits.py)."""
    if not _is_int(turns) or turns < 1:
        raise SettingsError(f"turns must be at least 1 (a whole number), got {_shown(turns)}")
    check_limit("turns", turns)
    if not (_is_number(budget) and budget >= 0):
        raise SettingsError(f"budget must be a number of zero or more cost units, got {_shown(budget)}")
    check_limit("budget", budget)
    if not _is_int(change_every) or change_every < 1:
        raise SettingsError(f"change-every must be at least 1 turn (a whole number), got {_shown(change_every)}")
    if realtime is not None and not (_is_number(realtime) and realtime > 0):
        raise SettingsError(f"realtime must be a positive number of seconds per turn, got {_shown(realtime)}")
    if realtime is not None:
        check_limit("realtime", realtime)
    if not _is_int(seed) or seed < 0:
        raise SettingsError(f"seed must be a whole number of 0 or more, got {_shown(seed)}")
    if seconds is not None and not (_is_number(seconds) and seconds > 0):
        raise SettingsError(f"the time allocation in seconds must be a positive number, got {_shown(seconds)}")
    if seconds is not None:
        check_limit("seconds", seconds, "the time allocation in seconds")
    if seconds is not None and realtime is not None:
        raise SettingsError("embodied costs (a time allocation in seconds) and real-time turns don't go together; "
                            "choose one")


def _shown(value) -> str:
    """A value as the refusal shows it: numbers as written, anything else with its type ('10' (a str))."""
    if _is_number(value) or _is_int(value):
        return f"{value}"
    return f"{value!r} (a {type(value).__name__})"


def check_costs(costs) -> None:
    """A cost of zero or more for each query kind, or SettingsError."""
    if not hasattr(costs, "keys") or set(costs) != set(DEFAULT_COSTS) or \
            not all(_is_number(value) and value >= 0 for value in costs.values()):
        raise SettingsError(f"costs must give a cost of 0 or more for each of {', '.join(DEFAULT_COSTS)}; "
                            f"got {dict(costs) if hasattr(costs, 'keys') else costs!r}")


@dataclass(frozen=True)
class EpisodeSettings:
    """Everything that defines one episode apart from its teacher; frozen, validated when made."""

    task: str = "pack-lunchbox"
    kitchen: str = "kitchen-1"
    strategy: str = DEFAULT_STRATEGY
    seed: int = 0
    turns: int = 30
    budget: float = 40.0
    change_every: int = 5
    realtime: float | None = None
    fetch_from_pantry: bool = True
    costs: dict = field(default_factory=lambda: dict(DEFAULT_COSTS))
    weights: dict | None = None  # DT with a user's weights: {"file": path, "values": {feature: weight}} (--weights)
    seconds: float | None = None  # embodied costs (thesis §8.2.2): the time allocation in seconds; turns is the cap
    until_budget_spent: bool = False  # the thesis's chapter-6 ending: stop once the budget is spent; turns is the bound

    def __post_init__(self):
        for name, value in (("task", self.task), ("kitchen", self.kitchen), ("strategy", self.strategy)):
            if not isinstance(value, str) or not value:
                raise SettingsError(f"{name} must be a name, got {value!r}")
        check_allocation(self.turns, self.budget, self.change_every, self.realtime, self.seed, self.seconds)
        for name in ("fetch_from_pantry", "until_budget_spent"):
            if not isinstance(getattr(self, name), bool):
                raise SettingsError(f"{name} must be true or false, got {getattr(self, name)!r}")
        check_costs(self.costs)
        check_questions(self.turns, self.budget, self.costs)
        if self.until_budget_spent:
            check_budget_pays_for_a_question(self.budget, self.costs)
        if self.weights is not None:
            weights_from_record(self.weights)

    def build_strategy(self):
        """The episode's strategy: the named one, or DT with the recorded user weights (shown as ``strategy``)."""
        if self.weights is None:
            return make_strategy(self.strategy)
        return weights_from_record(self.weights).strategy(self.strategy)

    def config(self, pictures: str | None = None):
        """The manager's allocation for this episode (``pictures``: folder for scene pictures, None: none)."""
        return EpisodeConfig(turns=self.turns, budget=self.budget, change_every=self.change_every, seed=self.seed,
                             costs=dict(self.costs), realtime=self.realtime, pictures=pictures,
                             fetch_from_pantry=self.fetch_from_pantry, seconds=self.seconds,
                             until_budget_spent=self.until_budget_spent)


def check_budget_pays_for_a_question(budget: float, costs: dict) -> None:
    """An episode that ends once its budget is spent needs a budget that pays for some question at the start,
    else it would end before its first turn (SettingsError naming the cheapest question)."""
    cheapest = min(float(costs[kind]) for kind in ("label", "demo", "feature"))
    if cheapest > budget + 1e-9:
        raise SettingsError(f"until_budget_spent: a budget of {budget:g} pays for no question (the cheapest costs "
                            f"{cheapest:g}), so the episode would end before its first turn; give a budget of at "
                            f"least {cheapest:g}")


def _is_int(value) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)


DEFAULTS = EpisodeSettings()


@dataclass
class EpisodeConfig:
    """One episode's allocation for the manager: T turns, budget B, a scene change every r turns.

    The defaults are :data:`dialog.settings.DEFAULTS`; ``EpisodeSettings.config()`` makes one.

    realtime: seconds per turn (None: turn-based); a late answer counts as none.
    pictures: folder for numbered scene pictures (None: no pictures).
    fetch_from_pantry: fetch an example the teacher says is absent, where the task allows.
    seconds: embodied costs (thesis §8.2.2): the time allocation in seconds (None: in turns); a turn lasts what
    it takes (pointing, fetching, saying the question, the answer; a quiet turn ``dialog.embodied``'s seconds),
    the scene changes every ``change_every`` nominal turns of seconds (as in real-time mode), and the episode
    ends once the seconds are used up or after ``turns`` turns (the cap).
    until_budget_spent: the thesis's chapter-6 ending: the episode ends after the turn in which the budget
    became spent (``learning.turn.budget_spent``), or after ``turns`` turns (the safety bound).
    """

    turns: int = DEFAULTS.turns
    budget: float = DEFAULTS.budget
    change_every: int = DEFAULTS.change_every
    seed: int = DEFAULTS.seed
    costs: dict = field(default_factory=lambda: dict(DEFAULTS.costs))
    realtime: float | None = DEFAULTS.realtime
    pictures: str | None = None
    fetch_from_pantry: bool = DEFAULTS.fetch_from_pantry
    seconds: float | None = None
    until_budget_spent: bool = False

    def __post_init__(self):
        check_allocation(self.turns, self.budget, self.change_every, self.realtime, seconds=self.seconds)
