"""The learner's state (thesis §7.3.1): a small composition of the training set and models, the scene, and the
budget and clock, each read through read-only views.

Three methods change it: ``observe_scene`` (a new scene), ``apply(action, answer)``
(one whole turn: the answer is learned and the turn is charged and recorded) and
``undo(change)`` (the teacher takes an answer back). Each checks everything
before it changes anything, and a refit that fails puts the old parts back, so
a bad call raises a ValueError naming what was wrong and leaves the state as it was.
"""

from __future__ import annotations

from dataclasses import replace
from types import MappingProxyType

import numpy as np

from learning.actions import DEFAULT_COSTS, Action, validate_costs
from learning.answers import AnswerError, Change, DemoRow, check_answer, feature_indices
from learning.concepts import ConceptModels, FeatureScaler, checked_rows
from learning.examples import Example
from learning.features.selection import SELECTION_METHODS, computational_subsets
from learning.limits import check_limit
from learning.progress import Progress, SceneView, read_only


class LearningState:
    """Everything a strategy may look at; the models are refit after every change of the training set."""

    def __init__(self, concepts, feature_names, budget: float, turns: int, costs: dict | None = None,
                 change_every: int = 1, variance: float = 4.0, length_scale: float | None = None,
                 feature_selection: str | None = None):
        """``feature_selection`` (None, "FI", "ES" or "ER", thesis §5.3): the models of concepts the teacher gave
        no feature subset for use the subset this method selects from the examples so far (one-vs-rest per
        concept, chosen anew at every refit), as the thesis's baselines do (figs. 6.4, 6.5); None: all features."""
        if not concepts:
            raise ValueError("at least one concept is needed")
        if feature_selection is not None and feature_selection not in SELECTION_METHODS[1:]:
            raise ValueError(f"feature_selection must be None or one of {', '.join(SELECTION_METHODS[1:])}, got "
                             f"{feature_selection!r}")
        self.feature_selection = feature_selection
        check_limit("concepts", len(concepts), "concepts")
        if budget < 0 or turns < 1:
            raise ValueError(f"budget must be >= 0 and turns >= 1, got budget {budget}, turns {turns}")
        self.concepts = tuple(concepts)
        self.feature_names = tuple(feature_names)
        self._progress = Progress(float(budget), int(turns), max(int(change_every), 1),
                                  validate_costs(costs or DEFAULT_COSTS))
        self._scene = SceneView(-1, np.zeros((0, len(self.feature_names))))
        self._examples: tuple[Example, ...] = ()
        self._subsets = MappingProxyType({c: None for c in self.concepts})
        self._scaler = FeatureScaler(len(self.feature_names))
        self._models = ConceptModels(self.concepts, variance=variance, length_scale=length_scale)
        self._version = 0  # bumps whenever the models are refit (what-if caches key on it)
        self._training_version = 0  # bumps whenever the training set changes
        self.cache: dict = {}  # what-if engines memoise (version, value) entries here; not learning state
        self._scene_P: np.ndarray | None = None
        self._training_arrays: tuple | None = None  # (examples, X, labels) of training_matrix
        self._selected: tuple | None = None  # (examples, subsets) of feature_selection: a scene change keeps them
        self._counts: tuple | None = None  # (examples, positives per concept) of counts_per_concept
        self._rows_kept: tuple | None = None  # (read-only rows, scaler, scaled rows) of _scaled_rows
        self._seconds = None  # embodied costs: a learning.decision.embodied.SecondsClock (None: time in turns)
        self._refit()

    # -- changing the state ---------------------------------------------------------
    def observe_scene(self, scene_id: int, X: np.ndarray) -> None:
        """A new observation of the scene; a changed scene also widens the scaler's pool."""
        X = checked_rows(X, len(self.feature_names), f"scene {scene_id} matrix (objects x features)")
        check_limit("scene_objects", len(X), f"objects (rows) in scene {scene_id}")
        if scene_id != self._scene.scene_id:
            scaler = self._scaler.copy()
            scaler.update(X)
            self._commit(scene=SceneView(scene_id, X), scaler=scaler)

    def apply(self, action: Action, answer=None) -> Change:
        """One turn: learn from the teacher's ``answer`` to ``action``, charge its cost and advance the clock.

        label: a concept name (None: skipped); demo: a scene object index, a :class:`DemoRow` (an object from
        elsewhere) or None (the teacher has none to show); feature: feature indices and/or names (None: skipped);
        no query: None. The action and the answer are checked first: an unaffordable or unknown action, or an
        answer that does not fit it, raises a ValueError and changes nothing.
        """
        self.check_action(action)
        self._progress.check_affordable(action)
        answer = check_answer(self, action, answer)
        scene, progress = self._scene, self._progress.after(action, self._scene.scene_id)
        if action.kind == "label":
            scene = replace(scene, asked=scene.asked | {int(action.object_index)})
        if action.kind == "none":
            self._commit(progress=progress)
            return Change("none")
        if answer is None:
            if action.kind == "demo":
                scene = replace(scene, absent=scene.absent | {action.concept})
            self._commit(progress=progress, scene=scene)
            return Change("absent" if action.kind == "demo" else "skipped", concept=getattr(action, "concept", None))
        if action.kind == "feature":
            previous = dict(self._subsets)
            subset = read_only(answer)
            self._commit(progress=progress, scene=scene, subsets={c: subset for c in self.concepts})
            return Change("features", features=tuple(int(i) for i in answer), previous_subsets=previous,
                          cost=self._progress.cost(action))
        if action.kind == "label":
            concept, obj, source, x = answer, int(action.object_index), "label", scene.X[action.object_index]
        elif isinstance(answer, DemoRow):
            concept, obj, source, x = action.concept, None, "demo", answer.x
        else:
            concept, obj, source, x = action.concept, answer, "demo", scene.X[answer]
        example = Example(read_only(x), concept, source, scene.scene_id)
        if source == "demo":
            scene = replace(scene, demonstrated=scene.demonstrated | scene.rows_equal_to(example.x))
        self._commit(progress=progress, scene=scene, examples=self._examples + (example,))
        return Change("example", concept=concept, object=obj, source=source, example=example,
                      cost=self._progress.cost(action))

    def undo(self, change: Change) -> None:
        """Take back what an applied answer taught (its example, or its feature subsets) and give back the budget its
        turn was charged; a taken-back feature answer re-opens the feature question. The turn itself stays over."""
        refunded = self._progress.refunded(change.cost, reopen_feature_query=change.kind == "features")
        if change.kind == "features" and change.previous_subsets is not None:
            self._commit(progress=refunded, subsets=change.previous_subsets)
            return
        if change.kind != "example":
            raise AnswerError(f"nothing to take back: a '{change.kind}' answer taught nothing")
        matches = [i for i, e in enumerate(self._examples) if e is change.example]
        if not matches:
            raise AnswerError(f"the {change.concept} example was already taken back")
        assert change.example is not None, "only a held example matched"
        examples = self._examples[:matches[-1]] + self._examples[matches[-1] + 1:]
        scene = self._scene
        if change.example.source == "demo" and change.example.scene_id == scene.scene_id:
            still_shown = frozenset().union(*(scene.rows_equal_to(e.x) for e in examples
                                              if e.source == "demo" and e.scene_id == scene.scene_id))
            scene = replace(scene, demonstrated=scene.demonstrated & still_shown)
        self._commit(progress=refunded, scene=scene, examples=examples)

    def add_prior(self, X, concepts, features=None) -> None:
        """What is known before the episode: examples (rows of ``X`` and their concepts, as label answers),
        which join the scaler's pool like a scene, and optionally every concept's feature indices."""
        X = checked_rows(X, len(self.feature_names), "prior examples (examples x features)")
        concepts = [str(c) for c in concepts]
        unknown = sorted(set(concepts) - set(self.concepts))
        if len(concepts) != len(X) or unknown:
            raise ValueError(f"prior examples need one known concept per row ({len(X)} rows, {len(concepts)} "
                             f"concepts, unknown {unknown}); known: {', '.join(self.concepts)}")
        scaler = self._scaler.copy()
        scaler.update(X)
        subsets = None
        if features is not None:
            subset = read_only(feature_indices(self.feature_names, features))
            subsets = {c: subset for c in self.concepts}
        added = tuple(Example(read_only(x), c, "label", -1) for x, c in zip(X, concepts))
        self._commit(scaler=scaler, examples=self._examples + added, subsets=subsets)

    def set_seconds_clock(self, clock) -> None:
        """Embodied costs (thesis §8.2.2): the allocation in seconds, the seconds used and what each action is
        expected to take (a :class:`~learning.decision.embodied.SecondsClock`), set by the caller each turn;
        None: time in turns."""
        self._seconds = clock

    seconds_clock = property(lambda self: self._seconds, doc="The embodied-cost clock, or None (time in turns).")

    def place_progress(self, **fields) -> None:
        """Put the budget and clock part-way through an episode (``spent``, ``turn``, ``history``,
        ``feature_query_asked``, ``last_query_scene_id``): benchmarks and tests draw such states."""
        self._progress = self._progress.placed(**fields)

    def _commit(self, progress: Progress | None = None, scene: SceneView | None = None, examples=None,
                subsets=None, scaler: FeatureScaler | None = None) -> None:
        """Swap in new parts and refit if the models' inputs changed; a failing refit puts the old parts back."""
        old = (self._progress, self._scene, self._examples, self._subsets, self._scaler, self._training_version)
        self._progress = progress or self._progress
        self._scene = scene or self._scene
        if examples is not None:
            self._examples = tuple(examples)
            self._training_version += 1
        if subsets is not None:
            self._subsets = MappingProxyType(dict(subsets))
        self._scaler = scaler or self._scaler
        if examples is None and subsets is None and scaler is None:
            if self._scene.X is not old[1].X:
                self._scene_P = None
            return
        try:
            self._refit()
        except Exception:
            (self._progress, self._scene, self._examples, self._subsets, self._scaler,
             self._training_version) = old
            self._refit()
            raise

    def _refit(self) -> None:
        X, labels = self.training_matrix()
        self._models.fit(self._scaler.transform(X), labels, self._subsets_to_fit(X, labels))
        self._scene_P = None
        self._version += 1

    def _subsets_to_fit(self, X: np.ndarray, labels) -> dict:
        """The teacher's feature subsets; with ``feature_selection``, a computed one where the teacher gave none."""
        subsets = dict(self._subsets)
        if self.feature_selection is None or len(X) == 0 or all(s is not None for s in subsets.values()):
            return subsets
        if self._selected is None or self._selected[0] is not self._examples:  # once per training set
            self._selected = (self._examples, computational_subsets(X, labels, self.concepts,
                                                                    method=self.feature_selection))
        chosen = self._selected[1]
        return {c: subsets[c] if subsets[c] is not None else chosen.get(c) for c in self.concepts}

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

    version = property(lambda self: self._version, doc="Bumps whenever the models are refit (caches key on it).")
    training_version = property(lambda self: self._training_version, doc="Bumps whenever the training set changes.")

    # -- the budget and the clock (read-only) ------------------------------------------
    @property
    def progress(self) -> Progress:
        return self._progress

    budget = property(lambda self: self._progress.budget)
    turns = property(lambda self: self._progress.turns)
    change_every = property(lambda self: self._progress.change_every)
    costs = property(lambda self: self._progress.costs)
    spent = property(lambda self: self._progress.spent)
    turn = property(lambda self: self._progress.turn, doc="Turns finished so far.")
    history = property(lambda self: self._progress.history, doc="The action kind of every finished turn.")
    feature_query_asked = property(lambda self: self._progress.feature_query_asked)
    last_query_scene_id = property(lambda self: self._progress.last_query_scene_id)
    remaining_budget = property(lambda self: self._progress.remaining_budget)

    def cost(self, action: Action) -> float:
        return self._progress.cost(action)

    def can_afford(self, action: Action) -> bool:
        return self._progress.can_afford(action)

    def quiet_run(self) -> int:
        """How many turns in a row, up to now, the learner asked nothing."""
        return self._progress.quiet_run()

    # -- the scene (read-only) -----------------------------------------------------------
    @property
    def scene(self) -> SceneView:
        return self._scene

    scene_id = property(lambda self: self._scene.scene_id)
    scene_X = property(lambda self: self._scene.X, doc="The current scene's rows (read-only).")
    asked_in_scene = property(lambda self: self._scene.asked, doc="Objects asked about with a label query.")
    demonstrated_in_scene = property(lambda self: self._scene.demonstrated, doc="Objects the teacher showed.")
    absent_in_scene = property(lambda self: self._scene.absent, doc="Concepts the teacher could not show here.")
    labelled_in_scene = property(lambda self: self._scene.labelled,
                                 doc="Objects whose concept the teacher gave in this scene (asked or shown).")

    # -- the training set and the models (read-only) ----------------------------------------
    @property
    def examples(self) -> tuple[Example, ...]:
        return self._examples

    @property
    def feature_subsets(self) -> MappingProxyType:
        """Each concept's feature indices as the teacher gave them (read-only), None for every feature."""
        return self._subsets

    @property
    def fitted_feature_subsets(self) -> MappingProxyType:
        """The feature indices each concept's model uses: the teacher's, or with ``feature_selection`` the
        computed ones where the teacher gave none (None: every feature)."""
        return MappingProxyType({c: self._models.subsets_.get(c) for c in self.concepts})

    @property
    def scaler(self) -> FeatureScaler:
        """A copy of the scaler the models' inputs are standardised with."""
        return self._scaler.copy()

    @property
    def models(self) -> ConceptModels:
        """The fitted concept models, to read (the state refits them; nothing else may)."""
        return self._models

    @property
    def kernel_variance(self) -> float:
        return self._models.variance

    @property
    def length_scale(self) -> float | None:
        """The fixed RBF length scale, or None (sqrt of the number of features used)."""
        return self._models.length_scale

    def concept_model(self, concept: str):
        """The fitted binary GP of ``concept`` (to read)."""
        return self._models.models_[concept]

    def model_columns(self, concept: str) -> np.ndarray:
        """The feature columns the model of ``concept`` uses."""
        return self._models.columns(concept, len(self.feature_names))

    def training_matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """The training rows and their concept names (read-only; built once per training set)."""
        if not self._examples:
            return np.zeros((0, len(self.feature_names))), np.array([], dtype=object)
        built = self._training_arrays
        if built is None or built[0] is not self._examples:  # the examples tuple is replaced on every change
            X = np.vstack([e.x for e in self._examples])
            labels = np.array([e.concept for e in self._examples], dtype=object)
            X.setflags(write=False)
            labels.setflags(write=False)
            built = self._training_arrays = (self._examples, X, labels)
        return built[1], built[2]

    def scaled_training(self) -> tuple[np.ndarray, np.ndarray]:
        """The training rows as the models see them (standardised) and their concept names."""
        X, labels = self.training_matrix()
        return self._scaler.transform(X), labels

    def scaled_scene(self) -> np.ndarray:
        """The current scene's rows, standardised like the training rows."""
        return self._scaler.transform(self.scene_X)

    def probabilities(self, X: np.ndarray | None = None) -> np.ndarray:
        """(n, |Y|) p(y|x) for ``X`` (default: the current scene, cached and read-only)."""
        if X is None:
            if self._scene_P is None:
                P = self._models.predict(self._scaler.transform(self.scene_X))
                P.setflags(write=False)
                self._scene_P = P
            return self._scene_P
        return self._models.predict(self._scaled_rows(X))

    def _scaled_rows(self, X) -> np.ndarray:
        """``X`` checked and standardised. Read-only rows (a held-out set) are taken as unchanging: the last
        such array is checked once and scaled once per scaler, not at every prediction (the same bits)."""
        kept = self._rows_kept
        if kept is not None and kept[0] is X and kept[1] is self._scaler:
            return kept[2]
        scaled = self._scaler.transform(checked_rows(X, len(self.feature_names), "rows to predict"))
        if isinstance(X, np.ndarray) and not X.flags.writeable:
            scaled.setflags(write=False)
            self._rows_kept = (X, self._scaler, scaled)
        return scaled

    def counts_per_concept(self) -> dict[str, int]:
        """Positive examples of each concept in the training set (counted once per training set; a new dict)."""
        if self._counts is None or self._counts[0] is not self._examples:
            counts = {c: 0 for c in self.concepts}
            for example in self._examples:
                counts[example.concept] += 1
            self._counts = (self._examples, counts)
        return dict(self._counts[1])

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The most probable concept name for each row."""
        return np.array(self.concepts, dtype=object)[np.argmax(self.probabilities(X), axis=1)]

