"""The learner's state: training set, feature subsets, current scene, budget and clock (thesis §7.3.1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from learning.actions import DEFAULT_COSTS, Action, validate_costs
from learning.concepts import ConceptModels, FeatureScaler, checked_row, checked_rows, checked_subset

SOURCES = ("label", "demo")  # how a training example may have been obtained


@dataclass(frozen=True)
class Example:
    """One labelled instance and how it was obtained ("demo" or "label")."""

    x: np.ndarray
    concept: str
    source: str
    scene_id: int


class LearningState:
    """Everything a strategy may look at; the models are refit after every change.

    Every mutator checks its arguments before it changes anything: a bad call raises a ValueError
    that names what was wrong and leaves the state exactly as it was.
    """

    def __init__(self, concepts, feature_names, budget: float, turns: int, costs: dict | None = None,
                 change_every: int = 1, variance: float = 4.0, length_scale: float | None = None):
        if not concepts:
            raise ValueError("at least one concept is needed")
        if budget < 0 or turns < 1:
            raise ValueError(f"budget must be >= 0 and turns >= 1, got budget {budget}, turns {turns}")
        self.concepts = tuple(concepts)
        self.feature_names = tuple(feature_names)
        self.budget = float(budget)
        self.turns = int(turns)
        self.change_every = max(int(change_every), 1)
        self.costs = validate_costs(costs or DEFAULT_COSTS)
        self.examples: list[Example] = []
        self.feature_subsets: dict[str, np.ndarray | None] = {c: None for c in self.concepts}
        self.feature_query_asked = False
        self.spent = 0.0
        self.turn = 0
        self.history: list[str] = []  # action kind of every finished turn
        self.scene_X = np.zeros((0, len(self.feature_names)))
        self.scene_id = -1
        self.asked_in_scene: set[int] = set()  # label queries asked in this scene
        self.demonstrated_in_scene: set[int] = set()  # scene objects the teacher showed as demonstrations
        self.absent_in_scene: set[str] = set()  # concepts the teacher could not show in this scene
        self._examples_at_last_turn = 0
        self.last_query_scene_id: int | None = None  # scene of the most recent query (None: never asked)
        self.version = 0  # bumps whenever the models are refit (what-if caches key on it)
        self.training_version = 0  # bumps whenever the training set changes
        self.cache: dict = {}  # what-if engines keep (version, value) entries here
        self.scaler = FeatureScaler(len(self.feature_names))
        self.models = ConceptModels(self.concepts, variance=variance, length_scale=length_scale)
        self._scene_P: np.ndarray | None = None
        self.refit()

    # -- the world ------------------------------------------------------------
    def observe_scene(self, scene_id: int, X: np.ndarray) -> None:
        """A new observation of the scene; a changed scene also widens the scaler's pool."""
        X = checked_rows(X, len(self.feature_names), f"scene {scene_id} matrix (objects x features)")
        if scene_id != self.scene_id:
            previous = (self.scene_id, self.scene_X, self.asked_in_scene, self.demonstrated_in_scene,
                        self.absent_in_scene, self.scaler)
            self.scene_id, self.scene_X = scene_id, X
            self.asked_in_scene = set()
            self.demonstrated_in_scene = set()
            self.absent_in_scene = set()
            self.scaler = self.scaler.copy()
            self.scaler.update(X)
            self._refit_or_restore(lambda: self._restore_scene(previous))

    def _restore_scene(self, previous) -> None:
        (self.scene_id, self.scene_X, self.asked_in_scene, self.demonstrated_in_scene, self.absent_in_scene,
         self.scaler) = previous

    # -- answers ----------------------------------------------------------------
    def add_example(self, x: np.ndarray, concept: str, source: str) -> None:
        """One more training instance: ``x`` (a row of feature values), its concept, and "label" or "demo"."""
        if concept not in self.concepts:
            raise ValueError(f"unknown concept '{concept}'; known: {', '.join(self.concepts)}")
        if source not in SOURCES:
            raise ValueError(f"unknown example source '{source}'; accepted: {', '.join(SOURCES)}")
        x = checked_row(x, len(self.feature_names), f"the example of '{concept}'")
        shown = self._scene_rows_equal_to(x) if source == "demo" else set()
        previous = (len(self.examples), set(self.demonstrated_in_scene), self.training_version)
        self.examples.append(Example(x, concept, source, self.scene_id))
        self.demonstrated_in_scene.update(shown)
        self.training_version += 1
        self._refit_or_restore(lambda: self._restore_examples(*previous))

    def _restore_examples(self, count: int, demonstrated: set[int], training_version: int) -> None:
        del self.examples[count:]
        self.demonstrated_in_scene, self.training_version = demonstrated, training_version

    def _refit_or_restore(self, restore) -> None:
        """Refit; if fitting fails (a bug or a numerical failure), undo the change and refit what was there."""
        try:
            self.refit()
        except Exception:
            restore()
            self.refit()
            raise

    def _scene_rows_equal_to(self, x: np.ndarray) -> set[int]:
        if x.shape != (len(self.feature_names),) or len(self.scene_X) == 0:
            return set()
        return set(np.flatnonzero(np.all(self.scene_X == x, axis=1)).tolist())

    def remove_last_example(self) -> Example | None:
        """Take back the most recent example (the teacher's "undo")."""
        if not self.examples:
            return None
        example = self.examples.pop()
        if example.source == "demo" and example.scene_id == self.scene_id:
            still_shown = {i for e in self.examples if e.source == "demo" and e.scene_id == self.scene_id
                           for i in self._scene_rows_equal_to(e.x)}
            self.demonstrated_in_scene &= still_shown
        self.training_version += 1
        self.refit()
        return example

    def set_feature_subset(self, indices) -> None:
        """Restrict every concept's classifier to the teacher's features from now on."""
        indices = checked_subset(indices, len(self.feature_names), "feature indices")
        previous = dict(self.feature_subsets)
        self.feature_subsets = {c: indices for c in self.concepts}
        self._refit_or_restore(lambda: setattr(self, "feature_subsets", previous))

    def record_turn(self, action: Action) -> None:
        """Charge the action's cost and advance the clock."""
        self.check_action(action)
        cost = self.cost(action)
        if cost > self.remaining_budget + 1e-9:
            raise ValueError(f"{action.kind} query costs {cost} but only {self.remaining_budget} is left")
        self.spent += cost
        self.history.append(action.kind)
        if action.kind == "feature":
            self.feature_query_asked = True
        if action.kind == "label":
            self.asked_in_scene.add(action.object_index)
        if action.kind == "demo" and len(self.examples) == self._examples_at_last_turn:
            self.absent_in_scene.add(action.concept)  # asked, but no example came back
        self._examples_at_last_turn = len(self.examples)
        if action.kind != "none":
            self.last_query_scene_id = self.scene_id
        self.turn += 1

    def check_action(self, action: Action) -> None:
        """A ValueError unless ``action`` is a known kind that fits this state (object in the scene, known
        concept)."""
        kind = getattr(action, "kind", None)
        if kind not in self.costs:
            raise ValueError(f"unknown action {action!r}; accepted kinds: {', '.join(self.costs)}")
        if kind == "label":
            index = getattr(action, "object_index", None)
            if isinstance(index, bool) or not isinstance(index, (int, np.integer)) \
                    or not 0 <= index < len(self.scene_X):
                raise ValueError(f"label query object {index!r} is not an object index of the current scene "
                                 f"(0..{len(self.scene_X) - 1})")
        if kind == "demo" and getattr(action, "concept", None) not in self.concepts:
            raise ValueError(f"demonstration query concept {getattr(action, 'concept', None)!r} is not one of "
                             f"{', '.join(self.concepts)}")

    # -- budget -------------------------------------------------------------------
    def cost(self, action: Action) -> float:
        kind = getattr(action, "kind", None)
        if kind not in self.costs:
            raise ValueError(f"unknown action {action!r}; accepted kinds: {', '.join(self.costs)}")
        return self.costs[kind]

    @property
    def remaining_budget(self) -> float:
        return self.budget - self.spent

    def can_afford(self, action: Action) -> bool:
        return self.cost(action) <= self.remaining_budget + 1e-9

    # -- interaction history ---------------------------------------------------------
    @property
    def labelled_in_scene(self) -> set[int]:
        """Scene objects whose concept the teacher already gave in this scene (asked or demonstrated)."""
        return self.asked_in_scene | self.demonstrated_in_scene

    def quiet_run(self) -> int:
        """How many turns in a row, up to now, the learner asked nothing."""
        run = 0
        for kind in reversed(self.history):
            if kind != "none":
                break
            run += 1
        return run

    # -- models -------------------------------------------------------------------
    def training_matrix(self) -> tuple[np.ndarray, np.ndarray]:
        if not self.examples:
            return np.zeros((0, len(self.feature_names))), np.array([], dtype=object)
        return np.vstack([e.x for e in self.examples]), np.array([e.concept for e in self.examples], dtype=object)

    def refit(self) -> None:
        X, labels = self.training_matrix()
        self.models.fit(self.scaler.transform(X), labels, self.feature_subsets)
        self._scene_P = None
        self.version += 1

    def scaled_training(self) -> tuple[np.ndarray, np.ndarray]:
        """The training rows as the models see them (standardised) and their concept names."""
        X, labels = self.training_matrix()
        return self.scaler.transform(X), labels

    def scaled_scene(self) -> np.ndarray:
        """The current scene's rows, standardised like the training rows."""
        return self.scaler.transform(self.scene_X)

    def probabilities(self, X: np.ndarray | None = None) -> np.ndarray:
        """(n, |Y|) p(y|x) for ``X`` (default: the current scene, cached)."""
        if X is None:
            if self._scene_P is None:
                self._scene_P = self.models.predict(self.scaler.transform(self.scene_X))
            return self._scene_P
        return self.models.predict(self.scaler.transform(checked_rows(X, len(self.feature_names), "rows to predict")))

    def counts_per_concept(self) -> dict[str, int]:
        """Positive examples of each concept in the training set."""
        counts = {c: 0 for c in self.concepts}
        for example in self.examples:
            counts[example.concept] += 1
        return counts

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The most probable concept name for each row."""
        return np.array(self.concepts, dtype=object)[np.argmax(self.probabilities(X), axis=1)]
