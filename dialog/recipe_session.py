"""Recipes end to end: demonstrations in the kitchen -> parameter models -> the arm carries the recipe out.

The glue between ``bullet_world.recipes.world`` (scenes, the scripted teacher,
observations), ``learning.recipes.grounding`` (eq. 4.1-4.3, GMM parameter models)
and ``robot.pick_place`` (grasp, carry, place). Used by ``teachbot recipe``,
``dialog/experiments/recipes/study.py`` (the chapter-4 experiments) and the tests.

* ``action_observations``: one demonstration as the learner's input; the rows
  of each "after" observation are matched to the "before" rows from perceived
  features (``recipe_tracking``), never from simulator ids.
* ``evaluate_demonstration``: the thesis's per-parameter test (§4.3.4) on a
  held-out demonstration.
* ``execute_recipe``: attention, object choice and a real pick-place per step;
  objects going to one location are put down where one demonstration put
  them (the most likely set that is free), else at a free, likely spot.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from bullet_world.recipes.tracking import match_rows
from bullet_world.recipes.world import RecipeDemonstration, RecipeObservation, RecipeWorld
from learning.errors import SettingsError
from learning.recipes.format import Recipe, RecipeStep, recipe_parameters
from learning.recipes.grounding import DEFAULT_TAU, ActionObservation, RecipeGrounding, Snapshot
from learning.recipes.parameter_models import ParameterModel
from robot.grasping import GraspTarget, Obstacle
from robot.pick_place import Manipulator, PickPlaceResult

PLACE_CANDIDATES = 300     # spots drawn from the end-location model when choosing where to put an object
PLACE_TAU = 2.0            # put-down spots lie this close (Mahalanobis) to the end-location model: its core
PLACE_SUPPORT_M = 0.03     # ... and this close to a spot where the teacher put something down
PLACE_GAP_M = 0.01         # free space kept around other perceived objects
HAND_RADIUS_M = 0.035      # the opening fingers sweep about this radius around the object's centre

# narrate(text, detail, body): tells a watcher (the viewer) what happens; body is the object meant, or None.
Narrate = Callable[[str, str, "int | None"], None]


DEMO_LIGHTING = ("alternate", "sweep")  # or the name of one lighting condition of the task


class NarratedRecipeWorld(RecipeWorld):
    """A ``RecipeWorld`` that tells ``narrate`` (when set) which demonstration the teacher gives.

    ``demo_lighting``: "alternate" (default) turns to the next lighting condition with every arrangement, so
    that even a few demonstrations see them all; "sweep" keeps ``RecipeWorld``'s order (every arrangement
    under the first condition, then under the next: the thesis's demonstrations 1-6, 7-12); a condition's
    name shows every demonstration under it. Arrangements and random draws are those of ``RecipeWorld``.
    """

    narrate: Narrate | None = None
    demo_lighting: str = "alternate"

    def demonstrate_once(self, number: int, layout: int, arrangement, lighting: str,
                         rng: np.random.Generator) -> RecipeDemonstration:
        lighting = demonstration_lighting(self.demo_lighting, list(self.setup.lighting), layout, lighting)
        if self.narrate is not None:
            steps = "; ".join(f"{obj}: {start} -> {end}" for obj, start, end in self.steps)
            self.narrate(f"Teacher: demonstration {number} (arrangement {layout + 1}, {lighting} light)", steps, None)
        return super().demonstrate_once(number, layout, arrangement, lighting, rng)


def demonstration_lighting(order: str, conditions: list[str], layout: int, swept: str) -> str:
    """The lighting of one demonstration: ``swept`` is the condition ``RecipeWorld``'s sweep order gives it."""
    if order == "sweep":
        return swept
    if order == "alternate":  # shifted by the arrangement: each one still meets every condition across sweeps
        return conditions[(conditions.index(swept) + layout) % len(conditions)]
    if order not in conditions:
        raise SettingsError(f"unknown demonstration lighting {order!r}; accepted: "
                            f"{', '.join([*DEMO_LIGHTING, *conditions])}")
    return order


def check_lighting(conditions, execution: str | None, demonstrations: str = "alternate") -> None:
    """Refuse a lighting the task does not have (before any work), naming the ones it has."""
    conditions = list(conditions)
    if execution is not None and execution not in conditions:
        raise SettingsError(f"--lighting {execution!r}: the task's lighting conditions are {', '.join(conditions)}")
    if demonstrations not in (*DEMO_LIGHTING, *conditions):
        raise SettingsError(f"--demo-lighting {demonstrations!r}: accepted are {', '.join(DEMO_LIGHTING)} or one "
                            f"of the task's lighting conditions ({', '.join(conditions)})")


def lighting_hint(demonstrations: Sequence[RecipeDemonstration], lighting: str, outcomes) -> str | None:
    """Why an execution may have failed: its lighting is one no demonstration was given in (None otherwise)."""
    seen = list(dict.fromkeys(demonstration.lighting for demonstration in demonstrations))
    failed = [outcome for outcome in outcomes if not outcome.success]
    if not failed or lighting in seen:
        return None
    return (f"Hint: the execution ran under {lighting} lighting, but every demonstration was given under "
            f"{' and '.join(seen)} lighting, so the object models never saw how the objects look under "
            f"{lighting} light ({len(failed)} of {len(outcomes)} steps failed). Demonstrate under it too "
            f"(--demo-lighting alternate, the default), or execute under {seen[0]} (--lighting {seen[0]}).")


def recipe_steps(recipe: Recipe) -> list[tuple[str, str, str]]:
    """The recipe as plain (object, start, end) triples for ``RecipeWorld``."""
    return [(step.object, step.start, step.end) for step in recipe.steps]


def snapshot(observation: RecipeObservation, order: np.ndarray | None = None) -> Snapshot:
    """The learner's view of an observation, rows optionally reordered."""
    rows = slice(None) if order is None else order
    return Snapshot(observation.appearance[rows], observation.locations[rows])


def action_observations(demonstration: RecipeDemonstration) -> list[ActionObservation]:
    """(before, after) snapshots of every step, after-rows matched to before-rows by perceived features."""
    result = []
    for step in demonstration.steps:
        before, after = step.before, step.after
        order = match_rows(before.appearance, before.locations, after.appearance, after.locations)
        result.append(ActionObservation(snapshot(before), snapshot(after, order)))
    return result


def ground(recipe: Recipe, demonstrations: Sequence[RecipeDemonstration], rng: np.random.Generator,
           grounding: RecipeGrounding | None = None) -> RecipeGrounding:
    """Learn (or extend) the parameter models of ``recipe`` from demonstrations (thesis §4.2.3)."""
    grounding = grounding if grounding is not None else RecipeGrounding(rng=rng)
    grounding.learn(recipe, [action_observations(demo) for demo in demonstrations])
    return grounding


def evaluate_demonstration(grounding: RecipeGrounding, recipe: Recipe, demonstration: RecipeDemonstration,
                           tau: float = DEFAULT_TAU) -> dict[str, list[bool]]:
    """Success of every parameter model on one held-out demonstration (thesis §4.3.4).

    Object parameter: among all objects in view before the step, the most
    likely one under the object model (eq. 4.3) is the true one and within tau.
    Start location: the true object before the step lies within tau of the
    model. End location: the true object after the step lies within tau of it.
    A parameter used by several steps gets one trial per step.
    """
    trials: dict[str, list[bool]] = {}
    for step, demonstrated in zip(recipe.steps, demonstration.steps):
        before, after = demonstrated.before, demonstrated.after
        object_model = grounding.object_models[step.object]
        likelihoods = object_model.log_likelihood(before.appearance)
        best = int(np.argmax(likelihoods))
        distance = float(object_model.mahalanobis(before.appearance[best : best + 1])[0])
        trials.setdefault(step.object, []).append(before.truth.roles[best] == step.object and distance <= tau)
        for name, observation in ((step.start, before), (step.end, after)):
            row = observation.truth.row_of_role(step.object)
            model = grounding.location_models[name]
            inside = float(model.mahalanobis(observation.locations[row : row + 1])[0]) <= tau
            trials.setdefault(name, []).append(inside)
    return trials


def parameter_names(recipe: Recipe) -> list[str]:
    parameters = recipe_parameters(recipe)
    return [*parameters.objects, *parameters.locations]


@dataclass
class StepOutcome:
    """What happened for one recipe step when the robot carried it out."""

    step: RecipeStep
    status: str                 # "done", "no-object-in-start-region", "no-likely-match", or a pick-place reason
    explanation: str
    chosen_kind: str | None     # hidden truth, for the report: what the chosen object really was
    correct_object: bool
    in_true_end_region: bool
    pick_place: PickPlaceResult | None

    @property
    def success(self) -> bool:
        return self.status == "done" and self.correct_object and self.in_true_end_region


class ModelRegion:
    """Inside = within ``tau`` (Mahalanobis, x and y only) of a learned location model."""

    def __init__(self, model: ParameterModel, recipe_world: RecipeWorld, tau: float):
        self.model, self.recipe_world, self.tau = model, recipe_world, tau

    def distance(self, xy_world) -> float:
        local = self.recipe_world.to_robot_frame(np.array([[xy_world[0], xy_world[1], 0.0]]))[0, :2]
        distances = []
        for mean, covariance in zip(self.model.means_, self.model.covariances_):
            offset = local - mean[:2]
            distances.append(float(np.sqrt(offset @ np.linalg.solve(covariance[:2, :2], offset))))
        return min(distances)

    def contains(self, xy) -> bool:
        return self.distance(xy) <= self.tau


def plan_put_downs(model: ParameterModel, demonstrated: list[list], steps: list[int], recipe_world: RecipeWorld,
                   observation: RecipeObservation, moving: int, tau: float = DEFAULT_TAU) -> dict[int, np.ndarray]:
    """Put-down spots (robot frame) for every step in ``steps``, all going to one end location.

    The robot copies the teacher: each demonstration put these steps' objects down at spots that fit
    together, so it takes the demonstration whose spots all lie in the model's core (``PLACE_TAU``) and
    clear of the objects already there, with the highest total likelihood under the end-location model.
    Empty when no demonstration fits.
    """
    best, best_score = {}, -np.inf
    for actions in demonstrated:
        spots = np.array([actions[j].end_location for j in steps])
        if np.any(model.mahalanobis(spots) > min(tau, PLACE_TAU)):
            continue
        if len(_free(model, spots, recipe_world, observation, moving, tau)) < len(spots):
            continue
        score = float(np.sum(model.log_likelihood(spots)))
        if score > best_score:
            best, best_score = dict(zip(steps, spots)), score
    return best


def choose_place(model: ParameterModel, recipe_world: RecipeWorld, observation: RecipeObservation, moving: int,
                 rng: np.random.Generator, tau: float = DEFAULT_TAU) -> np.ndarray | None:
    """A free put-down spot (robot frame) when the plan's spot is taken, or None when none is free.

    Spots are drawn from the end-location model and kept when they lie in its core (``PLACE_TAU``),
    near a spot where the teacher put something down (``PLACE_SUPPORT_M``) and clear of every other
    perceived object, counting the opening fingers; the most likely one wins.
    """
    component = rng.choice(len(model.weights_), size=PLACE_CANDIDATES, p=model.weights_)
    draws = np.array([rng.multivariate_normal(model.means_[j], model.covariances_[j]) for j in component])
    draws[:, 2] = model.means_[component, 2]
    nearest = np.min(np.linalg.norm(draws[:, None, :2] - model.samples_[None, :, :2], axis=2), axis=1)
    free = _free(model, draws[nearest <= PLACE_SUPPORT_M], recipe_world, observation, moving, tau)
    return free[int(np.argmax(model.log_likelihood(free)))] if len(free) else None


def _free(model: ParameterModel, candidates: np.ndarray, recipe_world: RecipeWorld,
          observation: RecipeObservation, moving: int, tau: float) -> np.ndarray:
    """The candidates (robot frame) in the model's core and clear of every other perceived object."""
    candidates = np.atleast_2d(candidates)
    if not len(candidates):
        return candidates
    candidates = candidates[model.mahalanobis(candidates) <= min(tau, PLACE_TAU)]
    spots = recipe_world.to_world_frame(candidates)[:, :2] if len(candidates) else np.zeros((0, 2))
    radii = np.array([0.5 * np.hypot(m.length, m.width) for m in observation.measurements])
    centres = np.array([m.centroid[:2] for m in observation.measurements])
    clear = np.ones(len(spots), dtype=bool)
    for i in range(len(radii)):
        if i != moving:
            needed = max(radii[moving], HAND_RADIUS_M) + radii[i] + PLACE_GAP_M
            clear &= np.linalg.norm(spots - centres[i], axis=1) >= needed
    return candidates[clear]


def execute_recipe(grounding: RecipeGrounding, recipe: Recipe, recipe_world: RecipeWorld,
                   manipulator: Manipulator, rng: np.random.Generator, tau: float = DEFAULT_TAU,
                   narrate: Narrate | None = None) -> list[StepOutcome]:
    """Carry the recipe out in the current scene (thesis §4.2.4, then a real pick-place per step).

    ``narrate``, when given, hears each step's choice before the arm moves and its outcome after.
    """
    narrate = narrate or (lambda text, detail, body: None)
    outcomes = []
    demonstrated = [actions for actions in grounding.demonstrated_actions if len(actions) == len(recipe.steps)]
    plans: dict[int, np.ndarray] = {}
    for number, step in enumerate(recipe.steps):
        observation = recipe_world.observe(rng)
        choice = grounding.choose_object(step, observation.appearance, observation.locations, tau=tau)
        if not choice.found:
            outcomes.append(StepOutcome(step, choice.status, choice.reason, None, False, False, None))
            narrate(f"Robot: {step}", choice.reason, None)
            continue
        row = choice.index
        kind, role, body = (observation.truth.kinds[row], observation.truth.roles[row],
                            observation.truth.body_ids[row])
        end_model = grounding.location_models[step.end]
        if number not in plans:
            sharing = [j for j in range(number, len(recipe.steps)) if recipe.steps[j].end == step.end]
            plans.update(plan_put_downs(end_model, demonstrated, sharing, recipe_world, observation, row, tau))
        planned = plans.get(number)
        if planned is not None and len(_free(end_model, planned, recipe_world, observation, row, tau)):
            place = planned
        else:
            place = choose_place(end_model, recipe_world, observation, row, rng, tau)
        if place is None:
            outcomes.append(StepOutcome(step, "no-free-place", f"no free spot at {step.end!r} for the object",
                                        kind, role == step.object, False, None))
            narrate(f"Robot: {step}", f"no free spot at {step.end!r}", body)
            continue
        target = GraspTarget.from_measurement(observation.measurements[row])
        place_xy = recipe_world.to_world_frame(place)[0, :2]
        obstacles = [Obstacle.from_measurement(m) for i, m in enumerate(observation.measurements) if i != row]
        narrate(f"Robot: {step}", choice.reason, body)
        result = manipulator.pick_place(target, place_xy, ModelRegion(end_model, recipe_world, tau), obstacles)
        true_xy = recipe_world.true_position(body)[:2]
        in_region = recipe_world.region(step.end).contains(true_xy)
        status = "done" if result.success else result.reason
        explanation = choice.reason + ("; placed" if result.success else f"; {result.reason}: {result.detail}")
        outcomes.append(StepOutcome(step, status, explanation, kind, role == step.object, in_region, result))
        narrate(f"Robot: {step}", "placed" if result.success else f"{result.reason}: {result.detail}", body)
    return outcomes


def execute_in_new_arrangement(grounding: RecipeGrounding, recipe: Recipe, recipe_world: RecipeWorld,
                               rng: np.random.Generator, grasp: str, lighting: str, tau: float = DEFAULT_TAU,
                               narrate: Narrate | None = None) -> list[StepOutcome]:
    """Light the kitchen, lay out a new arrangement and let the Panda carry the recipe out (``teachbot recipe``)."""
    from robot import Arm

    manipulator = Manipulator(Arm(recipe_world.world), grasp)
    try:
        recipe_world.set_lighting(lighting)
        recipe_world.arrange(recipe_world.new_arrangement(rng))
        return execute_recipe(grounding, recipe, recipe_world, manipulator, rng, tau, narrate=narrate)
    finally:
        manipulator.close()
