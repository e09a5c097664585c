"""The teaching loop as a library: observe a scene, ask, tell, predict, on plain arrays.

``TeachingLoop`` runs the timed, budgeted interaction of the thesis on top of
:class:`learning.state.LearningState` and the questioning strategies, and checks
the call order: ``observe`` (each call is a new scene), then per turn ``ask``
and ``tell``. Every call validates before it changes anything, so a bad call
raises a one-line error and leaves the loop exactly as it was. Concepts may be
any hashable labels; the state sees them as strings, the caller gets its own back.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass

import numpy as np

from learning.actions import ACTION_KINDS, DEFAULT_COSTS, Action, validate_costs
from learning.answers import AnswerError, Change
from learning.classifier import ConceptClassifier
from learning.concepts import checked_rows, normalise_rows
from learning.errors import SettingsError, TeachbotError
from learning.limits import check_limit, check_questions
from learning.state import LearningState
from learning.strategies import DEFAULT_STRATEGY, Strategy, make_strategy
from learning.turn import admissible, scene_due, scene_epoch

QUERY_KINDS = ACTION_KINDS


class CallOrderError(TeachbotError):
    """A loop method called out of turn: ``tell`` without ``ask``, ``ask`` twice, before a scene or after the end."""


@dataclass(frozen=True)
class Query:
    """The learner's question: ``kind`` is "label" (what is scene object ``object``?), "demo" (show me a
    ``concept``), "feature" (which features matter?) or "none" (nothing this turn)."""

    kind: str
    object: int | None
    concept: Hashable | None
    cost: float
    explanation: str


@dataclass(frozen=True)
class Turn:
    """One finished turn: its number (from 0), the scene (from 0), the question, the answer and what it did."""

    turn: int
    scene: int
    query: Query
    answer: object
    change: Change


class TeachingLoop:
    """A learner that asks a teacher about scenes of objects (rows of feature values) within a budget."""

    def __init__(self, concepts, strategy: str | Strategy = DEFAULT_STRATEGY, budget: float = 40, turns: int = 30,
                 change_every: int = 5, costs: dict | None = None, seed: int | np.random.Generator = 0,
                 feature_names=None):
        self.concepts, self._names = _concept_names(concepts)
        check_limit("concepts", len(self.concepts))  # before any state is made
        self._labels = dict(zip(self._names, self.concepts))
        self._internal = dict(zip(self.concepts, self._names))
        self.strategy = make_strategy(strategy) if isinstance(strategy, str) else strategy
        if not callable(getattr(self.strategy, "choose", None)):
            raise SettingsError(f"strategy must be a strategy name or have a choose(state, rng) method, "
                                f"got {strategy!r}")
        if not _number(budget) or budget < 0:
            raise SettingsError(f"budget must be a number >= 0, got {budget!r}")
        for name, value in (("turns", turns), ("change_every", change_every)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise SettingsError(f"{name} must be a whole number >= 1, got {value!r}")
        self.costs = validate_costs({"none": 0, **(DEFAULT_COSTS if costs is None else costs)})
        check_limit("turns", turns)
        check_questions(int(turns), float(budget), self.costs)
        self.budget, self.turns, self.change_every = float(budget), int(turns), int(change_every)
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self.feature_names = None if feature_names is None else tuple(str(n) for n in feature_names)
        if self.feature_names is not None and len(set(self.feature_names)) != len(self.feature_names):
            raise SettingsError("feature_names must be distinct")
        self.state: LearningState | None = None if self.feature_names is None else self._new_state()
        self.scenes = 0  # scenes observed so far
        self._scene_turn = 0  # the turn at which the latest scene was observed
        self._pending: tuple[Action, Query] | None = None
        self._history: list[Turn] = []

    def _new_state(self) -> LearningState:
        return LearningState(self._names, self.feature_names, self.budget, self.turns, costs=self.costs,
                             change_every=self.change_every,
                             feature_selection=getattr(self.strategy, "feature_selection", None))

    # -- the world ------------------------------------------------------------------
    def observe(self, X_scene) -> None:
        """A new scene: ``X_scene`` is (objects x features), one row per object the learner may ask about."""
        if self._pending is not None:
            raise CallOrderError(f"observe came while the {self._pending[1].kind} query of turn {self.turn} waits "
                                 f"for its answer; call tell(answer) first")
        if self.feature_names is None and np.ndim(X_scene) != 2:
            raise ValueError(f"the scene matrix must be 2-D (objects x features), got shape {np.shape(X_scene)}")
        n_features = len(self.feature_names) if self.feature_names is not None else np.shape(X_scene)[1]
        X = checked_rows(X_scene, n_features, "the scene matrix (objects x features)")
        if len(X) == 0:
            raise ValueError("a scene needs at least one object (row)")
        if self.state is None:
            self.feature_names = tuple(f"feature {i}" for i in range(n_features))
            self.state = self._new_state()
        self.state.observe_scene(self.scenes, X)
        self.scenes += 1
        self._scene_turn = self.turn

    @property
    def scene_due(self) -> bool:
        """True when the world should change before the next question: no scene yet, or a new block of
        ``change_every`` turns has begun since the last scene was observed."""
        return scene_due(self.turn, self.change_every,
                         None if self.scenes == 0 else scene_epoch(self._scene_turn, self.change_every))

    # -- one turn -----------------------------------------------------------------------
    def ask(self) -> Query:
        """The learner's question for this turn (the strategy's choice, or "none" when it cannot be asked)."""
        if self.state is None or self.scenes == 0:
            raise CallOrderError("no scene yet: call observe(X_scene) before ask()")
        if self._pending is not None:
            raise CallOrderError(f"ask came twice: the {self._pending[1].kind} query of turn {self.turn} waits for "
                                 f"its answer; call tell(answer) first")
        if self.done:
            raise CallOrderError(f"all {self.turns} turns are over; nothing more to ask")
        decision = self.strategy.choose(self.state, self.rng)
        action, reason = admissible(self.state, decision.action)
        query = Query(action.kind, getattr(action, "object_index", None),
                      self._labels.get(action.concept) if action.kind == "demo" else None, self.state.cost(action),
                      reason or decision.explanation)
        self._pending = (action, query)
        return query

    def tell(self, answer=None) -> Change:
        """The teacher's answer to the pending question: a concept (label query), a scene object index or None
        (demonstration query), feature indices or names or None (feature query), None (no query). The turn is
        charged and the clock advances; a wrong answer raises and the question stays open."""
        if self._pending is None:
            raise CallOrderError("tell came without a question: call ask() first")
        action, query = self._pending
        state = self.state_or_error()  # a pending question means a state
        internal = self._internal_answer(action, answer)
        change = state.apply(action, internal)
        self._history.append(Turn(state.turn - 1, state.scene_id, query, answer, change))
        self._pending = None
        return change

    def _internal_answer(self, action: Action, answer):
        """The answer in the state's terms (concept names as strings); ``LearningState.apply`` checks the rest."""
        if action.kind == "label" and answer is not None:
            plain = _plain(answer)
            try:
                name = self._internal.get(plain)
            except TypeError:  # unhashable
                name = None
            if name is not None and type(plain) is not type(self._labels[name]):
                name = None  # True, 1.0 and 1+0j equal the concept 1 but are not it
            if name is None:
                raise AnswerError(f"the answer to a label query is one of the concepts {list(self.concepts)} "
                                  f"(or None to skip), got {answer!r}")
            answer = name
        return answer

    # -- the learner --------------------------------------------------------------------
    def predict_proba(self, X) -> np.ndarray:
        """(n, |concepts|) p(concept | x) in the order of ``concepts``; a single row of features is one object."""
        return normalise_rows(self.state_or_error().probabilities(self._rows(X)))

    def predict(self, X) -> np.ndarray:
        """The most probable concept of each row, as the caller's labels."""
        P = self.predict_proba(X)
        return _label_array(self.concepts)[np.argmax(P, axis=1)]

    @property
    def classifier(self) -> ConceptClassifier:
        """A fitted ConceptClassifier holding a copy of what the loop learned (same scaling, examples, subsets)."""
        state = self.state_or_error()
        X, labels = state.training_matrix()
        codes = np.array([self._names.index(label) for label in labels], dtype=int)
        subsets = {self.concepts[self._names.index(c)]: s for c, s in state.fitted_feature_subsets.items()
                   if s is not None}
        classifier = ConceptClassifier(length_scale=state.length_scale, variance=state.kernel_variance)
        classifier.n_features_in_ = len(state.feature_names)
        classifier._install(_label_array(self.concepts), state.scaler, X, codes, subsets)
        return classifier

    def state_or_error(self) -> LearningState:
        if self.state is None:
            raise CallOrderError("nothing learned yet and no feature names: call observe(X_scene) first")
        return self.state

    def _rows(self, X) -> np.ndarray:
        n = len(self.state_or_error().feature_names)
        if np.ndim(X) == 1 and np.shape(X) == (n,):
            X = np.asarray(X)[None, :]
        return checked_rows(X, n, "rows to predict")

    # -- progress -----------------------------------------------------------------------
    @property
    def budget_left(self) -> float:
        return self.budget if self.state is None else self.state.remaining_budget

    @property
    def turn(self) -> int:
        """Turns finished so far."""
        return 0 if self.state is None else self.state.turn

    @property
    def done(self) -> bool:
        return self.turn >= self.turns

    @property
    def history(self) -> tuple[Turn, ...]:
        return tuple(self._history)

    @property
    def pending(self) -> Query | None:
        """The question waiting for its answer, if any."""
        return None if self._pending is None else self._pending[1]


def _concept_names(concepts) -> tuple[tuple, tuple[str, ...]]:
    """The caller's concepts (numpy scalars as plain values) and the string names the state uses for them."""
    if isinstance(concepts, (str, bytes)) or not np.iterable(concepts):
        raise SettingsError(f"concepts must be a sequence of labels such as np.unique(y), got {concepts!r}")
    labels = tuple(_plain(c) for c in concepts)
    if not labels:
        raise SettingsError("at least one concept is needed")
    wrong = [c for c in labels if c is None or isinstance(c, complex) or (isinstance(c, float) and c != c)]
    if wrong:
        raise SettingsError(f"concepts must be labels such as strings or whole numbers (not None, NaN or complex "
                         f"numbers), got {wrong[0]!r} in {list(labels)!r}")
    try:
        distinct = len(set(labels))
    except TypeError:
        raise SettingsError(f"concepts must be hashable labels (strings, numbers), got {list(labels)!r}") from None
    if distinct != len(labels):
        raise SettingsError(f"concepts must be distinct, got {list(labels)!r}")
    names = tuple(c if isinstance(c, str) else str(c) for c in labels)
    if len(set(names)) != len(names):
        raise SettingsError(f"concepts {list(labels)!r} are not distinct once written as text")
    return labels, names


def _label_array(labels: tuple) -> np.ndarray:
    """The labels as a numpy array of their own type (text, numbers), or of objects when they are mixed."""
    array = np.asarray(labels)
    if array.dtype.kind not in "USiufb" or any(_plain(a) != c for a, c in zip(array, labels)):
        array = np.array(labels, dtype=object)
    return array


def _plain(value):
    return value.item() if isinstance(value, np.generic) else value


def _number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
        and bool(np.isfinite(value))
