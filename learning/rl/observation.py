"""What a learned questioner sees and chooses from: fixed action slots and their decision features.

A reinforcement-learning policy needs a fixed-size observation and a fixed
list of actions, while the thesis's candidates change every turn (thesis
§7.3.1: one label query per scene object, one demonstration query per concept,
the feature query until it is asked). ``ObservationLayout`` fixes the list:

    slot 0            no query
    slot 1            the feature-subset query
    slots 2 .. 1+|Y|  a demonstration query per concept (the task's concept order)
    next m slots      a label query per scene object 0 .. m-1 (m: the task's largest scene)

and the observation, all in [0, 1]:

    phi(s)                    the 7 decision features now (eq. 7.2), 7 values
    E[phi(s') | a] per slot   each candidate's expected decision features at its own next
                              state (eq. 6.3, 7.1; the fast what-if engine), |slots| x 7 values,
                              zeros where the slot is not a candidate (``whatif=False`` leaves them out)
    mask                      1 where the slot is a candidate this turn (affordable, present), |slots| values
    allocation                (``allocation=True`` only: a policy trained across allocations, issue 40) the
                              episode's allocation, 4 values (``allocation_features``)

The same encoding serves the Gymnasium environment (dialog/rl/gym_env.py) and the
strategy that runs a trained policy (learning/strategies/rl_questioner.py), so a
policy sees in ``teachbot demo`` exactly what it saw in training.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from learning.actions import Action, DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.decision.candidates import candidate_actions, expected_decision_features
from learning.decision.features import FEATURE_NAMES, state_features
from learning.errors import SettingsError
from learning.whatif import WhatIfEngine, make_engine

N_FEATURES = len(FEATURE_NAMES)
ALLOCATION_NAMES = ("log_budget", "log_turns", "scene_share", "questions_per_turn")
ALLOCATION_SCALE = 1000.0  # budgets and turns are encoded as log(1 + x) / log(1 + ALLOCATION_SCALE), clipped to 1


def allocation_features(progress) -> np.ndarray:
    """The time and budget allocation of an episode as 4 numbers in [0, 1] (beyond the thesis: phi(s) of eq. 7.2
    holds only the fractions spent, so a policy trained on one allocation cannot tell another from it):
    log(1 + B) and log(1 + T) over log(1 + 1000); the share of the episode one scene lasts (change_every / T);
    and how many questions of the cheapest kind the budget buys per turn, min(1, B / c_min / T)."""
    paid = [cost for kind, cost in progress.costs.items() if kind != "none" and cost > 0]
    questions = progress.budget / min(paid) if paid else float(progress.turns)
    scale = np.log1p(ALLOCATION_SCALE)
    return np.clip(np.array([np.log1p(progress.budget) / scale, np.log1p(progress.turns) / scale,
                             progress.change_every / progress.turns, questions / progress.turns]), 0.0, 1.0)


@dataclass(frozen=True)
class Observation:
    """One turn's observation vector (float32), the mask of candidate slots and each slot's action (or None)."""

    vector: np.ndarray
    mask: np.ndarray
    actions: tuple[Action | None, ...]


@dataclass(frozen=True)
class ObservationLayout:
    """The fixed slots of a task: its concepts and its largest scene; ``whatif`` adds E[phi(s') | a] per slot."""

    concepts: tuple[str, ...]
    max_objects: int
    whatif: bool = True
    allocation: bool = False

    def __post_init__(self) -> None:
        if not self.concepts or len(set(self.concepts)) != len(self.concepts):
            raise SettingsError(f"a layout needs distinct concepts, got {list(self.concepts)}")
        if isinstance(self.max_objects, bool) or not isinstance(self.max_objects, int | np.integer) \
                or self.max_objects < 1:
            raise SettingsError(f"max_objects must be a whole number >= 1, got {self.max_objects!r}")

    @property
    def slots(self) -> tuple[Action, ...]:
        """The action of every slot, in slot order."""
        return (NoQuery(), FeatureQuery(), *(DemoQuery(c) for c in self.concepts),
                *(LabelQuery(i) for i in range(self.max_objects)))

    @property
    def n_actions(self) -> int:
        return 2 + len(self.concepts) + self.max_objects

    @property
    def size(self) -> int:
        """Length of the observation vector."""
        return (N_FEATURES + (self.n_actions * N_FEATURES if self.whatif else 0) + self.n_actions
                + (len(ALLOCATION_NAMES) if self.allocation else 0))

    def slot_of(self, action: Action) -> int:
        if action.kind == "none":
            return 0
        if action.kind == "feature":
            return 1
        if isinstance(action, DemoQuery):
            return 2 + self.concepts.index(action.concept)
        assert isinstance(action, LabelQuery)
        return 2 + len(self.concepts) + action.object_index

    def check_state(self, state) -> None:
        """SettingsError unless ``state`` fits this layout (same concepts, no larger scene)."""
        if tuple(state.concepts) != tuple(self.concepts):
            raise SettingsError(f"the policy was trained for the concepts {list(self.concepts)}; this task has "
                                f"{list(state.concepts)}")
        if len(state.scene_X) > self.max_objects:
            raise SettingsError(f"the policy was trained on scenes of at most {self.max_objects} objects; this "
                                f"scene has {len(state.scene_X)}")

    def encode(self, state, engine: str | WhatIfEngine = "fast") -> Observation:
        """The observation of a LearningState now (see the module docstring)."""
        self.check_state(state)
        candidates = candidate_actions(state)
        mask = np.zeros(self.n_actions, dtype=bool)
        actions: list[Action | None] = [None] * self.n_actions
        for action in candidates:
            slot = self.slot_of(action)
            mask[slot], actions[slot] = True, action
        parts = [state_features(state)]
        if self.whatif:
            rows = np.zeros((self.n_actions, N_FEATURES))
            expected = expected_decision_features(state, make_engine(engine), actions=candidates)
            for action, row in zip(expected.actions, expected.expected):
                rows[self.slot_of(action)] = row
            parts.append(rows.ravel())
        parts.append(mask.astype(float))
        if self.allocation:
            parts.append(allocation_features(state.progress))
        vector = np.clip(np.concatenate(parts), 0.0, 1.0).astype(np.float32)
        return Observation(vector, mask, tuple(actions))

    def record(self) -> dict:
        """The layout as a TOML-ready table (a policy file stores it)."""
        record = {"concepts": list(self.concepts), "max_objects": int(self.max_objects), "whatif": bool(self.whatif),
                  "features": list(FEATURE_NAMES)}
        if self.allocation:  # files of policies trained on one allocation stay as they were
            record |= {"allocation": True, "allocation_features": list(ALLOCATION_NAMES)}
        return record
