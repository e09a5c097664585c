"""The two small parts of the learner's state that are not the models: the budget and clock, and the scene.

Both are frozen: every change makes a new value, so the learning state can swap
a part in and, if refitting fails, swap the old one back.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from learning.actions import Action


def read_only(array: np.ndarray) -> np.ndarray:
    """A copy of ``array`` that cannot be written to."""
    copy = np.array(array, copy=True)
    copy.setflags(write=False)
    return copy


@dataclass(frozen=True)
class Progress:
    """The budget B and the clock: what was spent, how many turns are over, what each finished turn asked."""

    budget: float
    turns: int
    change_every: int
    costs: Mapping[str, float]
    spent: float = 0.0
    turn: int = 0
    history: tuple[str, ...] = ()  # action kind of every finished turn
    feature_query_asked: bool = False
    last_query_scene_id: int | None = None  # scene of the most recent query (None: never asked)

    def __post_init__(self):
        object.__setattr__(self, "costs", MappingProxyType(dict(self.costs)))

    def cost(self, action: Action) -> float:
        kind = getattr(action, "kind", "")  # "" is no kind: refused below, as is anything not an action
        if kind not in self.costs:
            raise ValueError(f"unknown action {action!r}; accepted kinds: {', '.join(self.costs)}")
        return self.costs[kind]

    @property
    def remaining_budget(self) -> float:
        return self.budget - self.spent

    def can_afford(self, action: Action) -> bool:
        return self.affords(self.cost(action))

    def affords(self, cost: float) -> bool:
        """Whether the remaining budget pays for ``cost`` (to within rounding)."""
        return cost <= self.remaining_budget + 1e-9

    def check_affordable(self, action: Action) -> None:
        cost = self.cost(action)
        if cost > self.remaining_budget + 1e-9:
            raise ValueError(f"{action.kind} query costs {cost:g} but only {self.remaining_budget:g} is left")

    def quiet_run(self) -> int:
        """How many turns in a row, up to now, the learner asked nothing."""
        run = 0
        for kind in reversed(self.history):
            if kind != "none":
                break
            run += 1
        return run

    def after(self, action: Action, scene_id: int) -> Progress:
        """The progress once ``action`` is charged and the clock has advanced one turn."""
        asked = action.kind != "none"
        return replace(self, spent=self.spent + self.cost(action), turn=self.turn + 1,
                       history=self.history + (action.kind,),
                       feature_query_asked=self.feature_query_asked or action.kind == "feature",
                       last_query_scene_id=scene_id if asked else self.last_query_scene_id)

    def refunded(self, cost: float, reopen_feature_query: bool) -> Progress:
        """The progress once a taken-back answer's ``cost`` is given back (the turn itself stays over); a taken-back
        feature answer also re-opens the feature question, which may be asked once (thesis §6.3)."""
        return replace(self, spent=max(0.0, self.spent - cost),
                       feature_query_asked=self.feature_query_asked and not reopen_feature_query)

    def placed(self, **fields) -> Progress:
        """This progress with some fields set (a state part-way through an episode); checked first."""
        unknown = sorted(set(fields) - {"spent", "turn", "history", "feature_query_asked", "last_query_scene_id"})
        if unknown:
            raise ValueError(f"unknown progress fields {unknown}; accepted: spent, turn, history, "
                             "feature_query_asked, last_query_scene_id")
        changes: dict[str, Any] = {k: tuple(v) if k == "history" else v for k, v in fields.items()}
        progress = replace(self, **changes)
        if not 0 <= progress.spent <= progress.budget + 1e-9:
            raise ValueError(f"spent must be within 0..{progress.budget:g}, got {progress.spent!r}")
        if not 0 <= progress.turn <= progress.turns:
            raise ValueError(f"turn must be within 0..{progress.turns}, got {progress.turn!r}")
        wrong = sorted({kind for kind in progress.history if kind not in self.costs})
        if wrong:
            raise ValueError(f"history holds unknown action kinds {wrong}; accepted: {', '.join(self.costs)}")
        return progress


@dataclass(frozen=True)
class SceneView:
    """The current scene (its rows read-only) and what the teacher said about it so far."""

    scene_id: int
    X: np.ndarray
    asked: frozenset[int] = field(default_factory=frozenset)  # objects asked about with a label query
    demonstrated: frozenset[int] = field(default_factory=frozenset)  # objects the teacher showed
    absent: frozenset[str] = field(default_factory=frozenset)  # concepts the teacher could not show here

    def __post_init__(self):
        if self.X.flags.writeable:
            object.__setattr__(self, "X", read_only(self.X))

    @property
    def labelled(self) -> frozenset[int]:
        """Objects whose concept the teacher already gave in this scene (asked or demonstrated)."""
        return self.asked | self.demonstrated

    def rows_equal_to(self, x: np.ndarray) -> frozenset[int]:
        if len(self.X) == 0 or x.shape != self.X.shape[1:]:
            return frozenset()
        return frozenset(np.flatnonzero(np.all(self.X == x, axis=1)).tolist())
