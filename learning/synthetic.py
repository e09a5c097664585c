"""A simulator-free concept-learning task for tests, benchmarks and quick strategy comparisons.

Each concept is a Gaussian blob in a few informative features; every other
feature is noise, as most of the robot's ~90 features are for the thesis's
tasks (§6.5.2). A scripted oracle answers label, demonstration and feature
queries from the hidden truth. ``run_episode`` plays the same timed, budgeted
loop as the dialog manager and ``TeachingLoop`` (the turn rules of ``learning.turn``: a new scene every
``change_every`` turns), with plain arrays, so every strategy can be exercised without PyBullet.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from learning.actions import Action
from learning.evaluation import accuracy
from learning.state import LearningState
from learning.turn import admissible, scene_due, scene_epoch

DEFAULT_CONCEPTS = ("main dish", "snack", "fruit", "beverage")


@dataclass(frozen=True)
class SyntheticTask:
    """Concepts as Gaussian blobs in ``n_informative`` of ``n_features`` features (positions drawn from ``seed``)."""

    concepts: tuple[str, ...] = DEFAULT_CONCEPTS
    n_features: int = 90
    n_informative: int = 6
    separation: float = 2.0
    seed: int = 0
    informative: np.ndarray = field(init=False, repr=False)
    means: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        if not 1 <= self.n_informative <= self.n_features:
            raise ValueError(f"n_informative must be in 1..n_features ({self.n_features}), got {self.n_informative}")
        rng = np.random.default_rng(self.seed)
        informative = np.sort(rng.choice(self.n_features, self.n_informative, replace=False))
        means = np.zeros((len(self.concepts), self.n_features))
        means[:, informative] = rng.normal(0.0, self.separation, (len(self.concepts), self.n_informative))
        object.__setattr__(self, "informative", informative)
        object.__setattr__(self, "means", means)

    @property
    def feature_names(self) -> tuple[str, ...]:
        return tuple(f"feature_{i}" for i in range(self.n_features))

    def sample(self, n_objects: int, rng: np.random.Generator, weights=None) -> tuple[np.ndarray, np.ndarray]:
        """``n_objects`` rows and their concept names; concepts drawn with ``weights`` (default uniform)."""
        codes = rng.choice(len(self.concepts), n_objects, p=weights)
        X = self.means[codes] + rng.normal(size=(n_objects, self.n_features))
        return X, np.array(self.concepts, dtype=object)[codes]

    def answer(self, action: Action, X: np.ndarray, truth: np.ndarray, rng: np.random.Generator):
        """The oracle's answer: a concept name, an object index (None if absent), or the informative features."""
        if action.kind == "label":
            return truth[action.object_index]
        if action.kind == "demo":
            members = np.flatnonzero(truth == action.concept)
            return int(members[rng.integers(len(members))]) if len(members) else None
        if action.kind == "feature":
            return self.informative
        return None


@dataclass
class EpisodeSummary:
    actions: list
    explanations: list
    accuracy: float
    spent: float


def run_episode(strategy, task: SyntheticTask, rng: np.random.Generator, budget: float = 40.0, turns: int = 30,
                change_every: int = 5, objects: int = 12, costs: dict | None = None, test_objects: int = 200,
                ) -> EpisodeSummary:
    """One teaching episode with the oracle; the returned accuracy is on ``test_objects`` held-out rows."""
    state = LearningState(task.concepts, task.feature_names, budget, turns, costs=costs, change_every=change_every,
                          feature_selection=getattr(strategy, "feature_selection", None))
    test_X, test_y = task.sample(test_objects, rng)
    actions, explanations = [], []
    X: np.ndarray  # both set at turn 0, the first scene
    truth: np.ndarray
    last_scene = None
    for turn in range(turns):
        if scene_due(turn, change_every, last_scene):  # learning.turn: the rules TeachingLoop and the dialog use
            X, truth = task.sample(objects, rng)
            last_scene = scene_epoch(turn, change_every)
            state.observe_scene(last_scene, X)
        decision = strategy.choose(state, rng)
        action, _ = admissible(state, decision.action)
        state.apply(action, task.answer(action, X, truth, rng))
        actions.append(action)
        explanations.append(decision.explanation)
    return EpisodeSummary(actions, explanations, accuracy(state.predict(test_X), test_y), state.spent)


def random_state(task: SyntheticTask, n_train: int, n_objects: int, rng: np.random.Generator,
                 feature_query_answered: bool = False, budget: float = 1000.0, turns: int = 2000,
                 change_every: int = 5, feature_selection: str | None = None) -> LearningState:
    """A learning state part-way through an episode: ``n_train`` examples with uneven classes, a scene of
    ``n_objects``, some budget spent, a random recent history; the benchmark, the tests and ``check_strategy``
    draw these (``feature_selection`` as the strategy's, see LearningState)."""
    state = LearningState(task.concepts, task.feature_names, budget, turns, change_every=change_every,
                          feature_selection=feature_selection)
    proportions = rng.dirichlet(np.full(len(task.concepts), 2.0))
    X, labels = task.sample(n_train, rng, proportions)
    scene_X, _ = task.sample(n_objects, rng)
    features = None
    if feature_query_answered:
        features = np.union1d(task.informative, rng.choice(task.n_features, 2, replace=False))
    state.add_prior(X, labels, features)
    state.observe_scene(0, scene_X)  # updates the scaler with the scene and refits
    turn = int(rng.integers(0, turns // 2))
    spent = float(rng.uniform(0.0, 0.5)) * budget
    history = [str(k) for k in rng.choice(["label", "demo", "none"], size=turn, p=[0.4, 0.2, 0.4])]
    state.place_progress(turn=turn, spent=spent, history=history, feature_query_asked=feature_query_answered)
    return state
