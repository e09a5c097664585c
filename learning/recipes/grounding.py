"""Grounding a recipe from demonstrations, and using the grounding (thesis §4.2.2-4.2.4).

Input data. A ``Snapshot`` is what perception reports for one world state: an
(n_objects x d) array of object appearance features, in the thesis
``(r, g, b, length, width, height)`` (colour in [0, 1], sizes in metres), and
an (n_objects x 3) array of bounding-box centroids ``(x, y, z)`` relative to
the robot, in metres. Row i of the *before* and *after* snapshots of one
action must be the same tracked object. A demonstration of a recipe is one
``ActionObservation`` (before, after) per recipe step, in order.

Which object moved (eq. 4.1, 4.2). o* = argmax_o dist(o_pre, o_post) with

    dist(o)^2 = ||loc_post(o) - loc_pre(o)||^2
                + appearance_weight^2 ||app_post(o) - app_pre(o)||^2.

By default ``appearance_weight = 0``: the norm uses the location features only,
because in the thesis data every action changed an object's position (§4.3.3)
while colour also changes with lighting and is in other units. Raise the
weight to let state changes (an empty bowl filled) count too.

Learning (§4.2.3). For each step, o*'s pre location updates the step's start
location model, its post location the end location model, and its pre and post
appearance the object model. Each model refits with k = 1..m, m = number of
demonstrations that contributed to it (see ``learning.recipes.parameter_models``).

Execution (§4.2.4, eq. 4.3). Attention goes to objects within Mahalanobis
distance tau of the start location model; among those the object with the
highest likelihood under the object model is chosen, and accepted only if it
is also within tau of that model ("likely match"). Otherwise the result says
"no match" and why; nothing is raised for an object that is not found.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from learning.errors import SettingsError
from learning.recipes.format import Recipe, RecipeStep, recipe_parameters
from learning.recipes.parameter_models import ParameterModel

OBJECT_FEATURE_NAMES: tuple[str, ...] = ("r", "g", "b", "length", "width", "height")
LOCATION_FEATURE_NAMES: tuple[str, ...] = ("x", "y", "z")
# Sensor-noise standard deviations used as the covariance prior (see parameter_models).
DEFAULT_OBJECT_NOISE_STD: tuple[float, ...] = (0.03, 0.03, 0.03, 0.01, 0.01, 0.01)
DEFAULT_LOCATION_NOISE_STD: tuple[float, ...] = (0.02, 0.02, 0.02)
DEFAULT_TAU = 3.0

MATCH = "match"
NO_OBJECT_IN_START_REGION = "no-object-in-start-region"
NO_LIKELY_MATCH = "no-likely-match"


@dataclass(frozen=True, eq=False)
class Snapshot:
    """Per-object appearance (n x d) and location (n x 3) of one world state."""

    features: np.ndarray
    locations: np.ndarray

    def __post_init__(self) -> None:
        features, locations = _checked_scene(self.features, self.locations, "snapshot")
        object.__setattr__(self, "features", features)
        object.__setattr__(self, "locations", locations)

    @property
    def n_objects(self) -> int:
        return int(self.features.shape[0])


@dataclass(frozen=True, eq=False)
class ActionObservation:
    """The snapshots before and after one demonstrated action (thesis §4.2.2)."""

    before: Snapshot
    after: Snapshot


@dataclass(frozen=True, eq=False)
class DemonstratedAction:
    """What one demonstrated action did: which object moved, from where to where."""

    moved_index: int
    change: float
    changes: np.ndarray
    start_location: np.ndarray
    end_location: np.ndarray
    appearance_before: np.ndarray
    appearance_after: np.ndarray


@dataclass(frozen=True, eq=False)
class ObjectChoice:
    """Result of ``RecipeGrounding.choose_object``; ``index`` is None unless ``found``.

    ``status`` is ``"match"``, ``"no-object-in-start-region"`` or
    ``"no-likely-match"``; ``reason`` says it in a sentence. The arrays hold,
    for every scene object, the distance to the start location model, the
    distance to the object model and the log-likelihood under it.
    """

    step: RecipeStep
    status: str
    index: int | None
    reason: str
    candidates: tuple[int, ...]
    location_distances: np.ndarray
    object_distances: np.ndarray
    object_log_likelihoods: np.ndarray

    @property
    def found(self) -> bool:
        return self.status == MATCH


def parse_action(
    before: Snapshot,
    after: Snapshot,
    appearance_weight: float = 0.0,
    min_change: float = 0.0,
) -> DemonstratedAction:
    """Find the object the teacher acted on, o* of eq. 4.2 (norm in the module doc).

    Raises ValueError if the snapshots do not match or no object changed by
    more than ``min_change`` (the thesis assumes a visible change, §4.2.2).
    """
    if before.n_objects != after.n_objects:
        raise ValueError(
            f"before has {before.n_objects} objects but after has {after.n_objects}; "
            "accepted: the same tracked objects, row by row, in both snapshots"
        )
    if before.features.shape[1] != after.features.shape[1]:
        raise ValueError(
            f"before has {before.features.shape[1]} appearance features but after has "
            f"{after.features.shape[1]}; accepted: the same features in both snapshots"
        )
    if not np.isfinite(appearance_weight) or appearance_weight < 0:
        raise ValueError(f"appearance_weight must be a number >= 0, got {appearance_weight!r}")
    changes = object_changes(before, after, appearance_weight)
    moved = int(np.argmax(changes))
    if changes[moved] <= min_change:
        raise ValueError(
            f"no object changed by more than {min_change} (largest change {changes[moved]:.3g}); "
            "accepted: snapshots before and after an action that moved an object"
        )
    return DemonstratedAction(
        moved_index=moved,
        change=float(changes[moved]),
        changes=changes,
        start_location=before.locations[moved].copy(),
        end_location=after.locations[moved].copy(),
        appearance_before=before.features[moved].copy(),
        appearance_after=after.features[moved].copy(),
    )


def object_changes(before: Snapshot, after: Snapshot, appearance_weight: float = 0.0) -> np.ndarray:
    """dist(o_pre, o_post) of eq. 4.1 for every object (norm in the module doc)."""
    squared = np.sum((after.locations - before.locations) ** 2, axis=1)
    if appearance_weight:
        squared = squared + appearance_weight**2 * np.sum((after.features - before.features) ** 2, axis=1)
    return np.sqrt(squared)


@dataclass
class RecipeGrounding:
    """One ParameterModel per recipe parameter, learned from demonstrations (§4.2.3).

    Parameters shared between recipes (``bowl``, ``counter``) share a model,
    so a grounding can learn several recipes in one kitchen.
    """

    object_noise_std: Sequence[float] | float = DEFAULT_OBJECT_NOISE_STD
    location_noise_std: Sequence[float] | float = DEFAULT_LOCATION_NOISE_STD
    max_components: int | None = None
    appearance_weight: float = 0.0
    rng: np.random.Generator | None = None
    object_models: dict[str, ParameterModel] = field(default_factory=dict, init=False)
    location_models: dict[str, ParameterModel] = field(default_factory=dict, init=False)
    demonstrated_actions: list[list[DemonstratedAction]] = field(default_factory=list, init=False)

    def __post_init__(self) -> None:
        if self.rng is None:
            self.rng = np.random.default_rng(0)
        if not isinstance(self.rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator or None, got {type(self.rng).__name__}")
        self._object_samples: dict[str, list[np.ndarray]] = {}
        self._location_samples: dict[str, list[np.ndarray]] = {}
        self._object_demos: dict[str, int] = {}
        self._location_demos: dict[str, int] = {}

    def learn(
        self, recipe: Recipe, demonstrations: Sequence[Sequence[ActionObservation]]
    ) -> list[list[DemonstratedAction]]:
        """Add demonstrations of ``recipe`` and refit the models they touch.

        Each demonstration is one ActionObservation per recipe step, in order.
        Returns the parsed actions, one list per demonstration.
        """
        if not isinstance(recipe, Recipe):
            raise ValueError(f"recipe must be a Recipe, got {type(recipe).__name__}")
        parsed_all = [self._parse_demonstration(recipe, demo, n) for n, demo in enumerate(demonstrations, 1)]
        if not parsed_all:
            raise ValueError("no demonstrations given; accepted: a list of at least one demonstration")
        self._check_appearance_dimensions(recipe, parsed_all)
        for parsed in parsed_all:
            objects_seen: set[str] = set()
            locations_seen: set[str] = set()
            for step, action in zip(recipe.steps, parsed):
                appearance = np.vstack([action.appearance_before, action.appearance_after])
                self._object_samples.setdefault(step.object, []).append(appearance)
                self._location_samples.setdefault(step.start, []).append(action.start_location[None])
                self._location_samples.setdefault(step.end, []).append(action.end_location[None])
                objects_seen.add(step.object)
                locations_seen.update((step.start, step.end))
            for name in objects_seen:
                self._object_demos[name] = self._object_demos.get(name, 0) + 1
            for name in locations_seen:
                self._location_demos[name] = self._location_demos.get(name, 0) + 1
        parameters = recipe_parameters(recipe)
        for name in parameters.objects:
            self._refit(name, self.object_models, self._object_samples, self._object_demos, self.object_noise_std)
        for name in parameters.locations:
            self._refit(
                name, self.location_models, self._location_samples, self._location_demos, self.location_noise_std
            )
        self.demonstrated_actions.extend(parsed_all)
        return parsed_all

    def choose_object(
        self,
        step: RecipeStep,
        scene_features: np.ndarray,
        scene_locations: np.ndarray,
        tau: float = DEFAULT_TAU,
    ) -> ObjectChoice:
        """Pick the object for ``step`` in a new scene (thesis §4.2.4, eq. 4.3)."""
        if not np.isfinite(tau) or tau <= 0:
            raise SettingsError(f"tau must be a positive number, got {tau!r}")
        features, locations = _checked_scene(scene_features, scene_locations, "scene")
        start_model = self._model_for(self.location_models, step.start, "location")
        object_model = self._model_for(self.object_models, step.object, "object")
        if features.shape[1] != object_model.dimension_:
            raise ValueError(
                f"scene_features has {features.shape[1]} features per object but the model of "
                f"{step.object!r} was learned on {object_model.dimension_}"
            )
        location_distances = start_model.mahalanobis(locations)
        object_distances = object_model.mahalanobis(features)
        log_likelihoods = object_model.log_likelihood(features)
        candidates = tuple(int(i) for i in np.flatnonzero(location_distances <= tau))

        def result(status: str, index: int | None, reason: str) -> ObjectChoice:
            return ObjectChoice(
                step, status, index, reason, candidates, location_distances, object_distances, log_likelihoods
            )

        if not candidates:
            nearest = float(location_distances.min())
            return result(
                NO_OBJECT_IN_START_REGION,
                None,
                f"no object lies within tau={tau:g} of {step.start!r} (nearest at distance {nearest:.2f})",
            )
        best = max(candidates, key=lambda i: log_likelihoods[i])
        if object_distances[best] > tau:
            return result(
                NO_LIKELY_MATCH,
                None,
                f"none of the {len(candidates)} objects at {step.start!r} looks like {step.object!r} "
                f"(most likely, object {best}, is at distance {object_distances[best]:.2f} > tau={tau:g})",
            )
        return result(
            MATCH,
            best,
            f"object {best} at {step.start!r} matches {step.object!r} (distance {object_distances[best]:.2f})",
        )

    def end_location_target(self, step: RecipeStep) -> np.ndarray:
        """Where to place for ``step``: mean (x, y, z) of the heaviest end-location component."""
        return self._model_for(self.location_models, step.end, "location").heaviest_component_mean()

    def _parse_demonstration(
        self, recipe: Recipe, demonstration: Sequence[ActionObservation], number: int
    ) -> list[DemonstratedAction]:
        if len(demonstration) != len(recipe.steps):
            raise ValueError(
                f"demonstration {number} has {len(demonstration)} actions but recipe {recipe.name!r} "
                f"has {len(recipe.steps)} steps; accepted: one (before, after) observation per step"
            )
        parsed = []
        for step_number, observation in enumerate(demonstration, 1):
            if not isinstance(observation, ActionObservation):
                raise ValueError(
                    f"demonstration {number}, step {step_number}: expected an ActionObservation, "
                    f"got {type(observation).__name__}"
                )
            try:
                parsed.append(parse_action(observation.before, observation.after, self.appearance_weight))
            except ValueError as error:
                raise ValueError(f"demonstration {number}, step {step_number}: {error}") from None
        return parsed

    def _check_appearance_dimensions(self, recipe: Recipe, parsed_all: list[list[DemonstratedAction]]) -> None:
        """Reject mismatched feature counts before any model is touched."""
        noise = np.atleast_1d(np.asarray(self.object_noise_std, dtype=float))
        for number, parsed in enumerate(parsed_all, 1):
            for step, action in zip(recipe.steps, parsed):
                dimension = action.appearance_before.size
                known = self._object_samples.get(step.object)
                expected = known[0].shape[1] if known else (noise.size if noise.size > 1 else dimension)
                if dimension != expected:
                    raise ValueError(
                        f"demonstration {number}: {step.object!r} has {dimension} appearance "
                        f"features; expected {expected} (the object noise_std and earlier "
                        "demonstrations fix the feature count)"
                    )

    def _refit(
        self,
        name: str,
        models: dict[str, ParameterModel],
        samples: dict[str, list[np.ndarray]],
        demos: dict[str, int],
        noise_std: Sequence[float] | float,
    ) -> None:
        if name not in models:
            assert self.rng is not None, "__post_init__ replaces rng=None with a Generator"
            models[name] = ParameterModel(noise_std, self.max_components, rng=self.rng.spawn(1)[0])
        models[name].fit(np.vstack(samples[name]), n_demonstrations=demos[name])

    @staticmethod
    def _model_for(models: dict[str, ParameterModel], name: str, kind: str) -> ParameterModel:
        if name not in models:
            known = ", ".join(sorted(models)) or "none yet"
            raise ValueError(f"no {kind} model for {name!r}; learned {kind}s: {known}")
        return models[name]


def _checked_scene(features: np.ndarray, locations: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    features = np.asarray(features, dtype=float)
    locations = np.asarray(locations, dtype=float)
    if features.ndim != 2 or features.shape[0] == 0 or features.shape[1] == 0:
        raise ValueError(
            f"{what} features must be a 2-D array (n_objects x d), n_objects >= 1, got shape {features.shape}"
        )
    if locations.ndim != 2 or locations.shape[1] != 3:
        raise ValueError(f"{what} locations must be an (n_objects x 3) array, got shape {locations.shape}")
    if locations.shape[0] != features.shape[0]:
        raise ValueError(
            f"{what} has {features.shape[0]} feature rows but {locations.shape[0]} location rows; "
            "accepted: one row per object in both"
        )
    if not (np.all(np.isfinite(features)) and np.all(np.isfinite(locations))):
        raise ValueError(f"{what} contains NaN or infinite values; accepted: finite numbers")
    return features.copy(), locations.copy()
