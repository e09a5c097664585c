"""``teachbot recipe``: learn a recipe's objects and locations from demonstrations, then carry it out.

    teachbot recipe --recipe serve-pasta --kitchen kitchen-1 --demos 5 --execute

A scripted teacher demonstrates the recipe ``--demos`` times in the kitchen
(thesis §4.3.2: arrangements varied step by step, two lighting conditions);
the robot finds the moved object of every step from the camera (eq. 4.1, 4.2),
fits one Gaussian-mixture model per recipe parameter (BIC over k = 1..m) and
prints them. With ``--execute`` it then looks at a new arrangement and carries
the recipe out with the Panda: attention to the start location, the most
likely object within tau, a real pick-place to a free spot of the end
location. ``--viewer`` mirrors the kitchen live in meshcat (``--viewer-export``
writes the run as one HTML page); ``--json`` ends the output with one JSON line.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bullet_world.recipes.setup import load_recipe_setup
from dialog.commands._arguments import add_kitchen_option, add_task_option, positive_int, seed
from dialog.commands._json import print_json
from dialog.recipe_session import (
    NarratedRecipeWorld,
    StepOutcome,
    check_lighting,
    execute_in_new_arrangement,
    ground,
    lighting_hint,
    parameter_names,
    recipe_steps,
)
from dialog.viewer import add_viewer_option, hold_viewer, start_viewer, stop_viewer
from learning.recipes.format import Recipe, builtin_recipe_names, load_builtin_recipe, load_recipe
from learning.recipes.grounding import DEFAULT_TAU, RecipeGrounding
from robot.grasping import GRASP_MODES

CAPTION_DWELL_S = 1.5  # seconds each caption holds in an exported page (--viewer-export)


def register(commands) -> None:
    parser = commands.add_parser(
        "recipe", help="learn a recipe from demonstrations and carry it out with the arm",
        description="A scripted teacher demonstrates the recipe --demos times; the robot finds the object moved in "
                    "every step, fits a Gaussian-mixture model per recipe parameter and prints them. --execute then "
                    "carries the recipe out with the arm in a new arrangement.")
    parser.add_argument("--recipe", default="serve-pasta",
                        help=f"built-in recipe ({', '.join(builtin_recipe_names())}) or a recipe .toml file")
    add_task_option(parser, None, help_default="the recipe's name")
    add_kitchen_option(parser, "kitchen-1")
    parser.add_argument("--demos", type=positive_int, default=5, help="demonstrations to learn from (default 5)")
    parser.add_argument("--execute", action="store_true", help="carry the recipe out with the arm afterwards")
    parser.add_argument("--lighting", default=None,
                        help="lighting for the execution scene, one of the task's conditions (default: the first)")
    parser.add_argument("--demo-lighting", default="alternate", metavar="ORDER",
                        help="lighting of the demonstrations: alternate (default: the next condition with every "
                             "arrangement), sweep (all arrangements under the first condition, then the next, as "
                             "in the thesis) or one condition's name")
    parser.add_argument("--grasp", choices=GRASP_MODES, default=GRASP_MODES[0], help="grasp mode (default friction)")
    parser.add_argument("--tau", type=positive_float, default=DEFAULT_TAU,
                        help=f"Mahalanobis threshold (default {DEFAULT_TAU:g})")
    parser.add_argument("--seed", type=seed, default=0, help="one seed for every random choice (default 0)")
    add_viewer_option(parser)
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the run")
    parser.set_defaults(handler=run)


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got '{text}'") from None
    if not value > 0 or not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {value}")
    return value


def load_any_recipe(name_or_path: str) -> Recipe:
    if name_or_path.endswith(".toml"):
        return load_recipe(name_or_path)
    return load_builtin_recipe(name_or_path)


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    recipe = load_any_recipe(args.recipe)
    check_lighting(load_recipe_setup(args.task or recipe.name).lighting, args.lighting, args.demo_lighting)
    rng = np.random.default_rng(args.seed)
    with NarratedRecipeWorld(recipe_steps(recipe), task=args.task or recipe.name, kitchen=args.kitchen,
                             seed=args.seed) as world:
        world.demo_lighting = args.demo_lighting
        viewer = start_viewer(args, world.world)
        try:
            if viewer is not None:
                viewer.start_recording()
                world.narrate = _narrator(viewer, world)
            summary = _session(args, recipe, world, rng, world.narrate)
            summary["seconds"] = round(time.perf_counter() - started, 1)
            if args.json:
                print_json(summary)
            hold_viewer(args, viewer)
        finally:
            stop_viewer(viewer)
    return 0


def _session(args: argparse.Namespace, recipe: Recipe, world: NarratedRecipeWorld, rng: np.random.Generator,
             narrate) -> dict:
    """Demonstrations, grounding and (with --execute) the arm carrying the recipe out; the JSON summary."""
    print(f"Recipe {recipe.name} in {world.kitchen.name} (household {world.household.name}): "
          + "; ".join(str(step) for step in recipe.steps))
    demonstrations = world.demonstrate(args.demos, rng)
    grounding = ground(recipe, demonstrations, rng)
    parsed_right = _print_demonstrations(recipe, demonstrations, grounding)
    _print_models(recipe, grounding)
    summary = {"recipe": recipe.name, "kitchen": world.kitchen.name, "demos": args.demos, "seed": args.seed,
               "moved_object_found": parsed_right, "parameters": _model_summary(recipe, grounding)}
    if args.execute:
        lighting = args.lighting or next(iter(world.setup.lighting))
        print(f"\nExecution in a new arrangement under {lighting} lighting:")
        outcomes = execute_in_new_arrangement(grounding, recipe, world, rng, args.grasp, lighting, args.tau, narrate)
        _print_outcomes(outcomes)
        hint = lighting_hint(demonstrations, world.lighting_name, outcomes)
        if hint:
            print(hint)
            summary["hint"] = hint
        summary["steps"] = [_outcome_summary(outcome) for outcome in outcomes]
        summary["success"] = all(outcome.success for outcome in outcomes)
        if narrate is not None:
            done = sum(outcome.success for outcome in outcomes)
            narrate(f"Robot: {recipe.name} done", f"{done} of {len(outcomes)} steps carried out correctly", None)
    return summary


def _narrator(viewer, world: NarratedRecipeWorld):
    """Captions in the viewer; the object meant is marked (its number in the world's order)."""
    def narrate(text: str, detail: str = "", body: int | None = None) -> None:
        bodies = world.world.object_bodies
        viewer.caption(text, detail, bodies.index(body) if body in bodies else None, dwell_s=CAPTION_DWELL_S)
    return narrate


def _print_demonstrations(recipe: Recipe, demonstrations, grounding: RecipeGrounding) -> str:
    """One line per demonstration: which object the learner saw move in each step (eq. 4.2)."""
    print(f"\n{len(demonstrations)} demonstrations; the object that moved most in each step (eq. 4.1, 4.2):")
    right = total = 0
    for demonstration, parsed in zip(demonstrations, grounding.demonstrated_actions[-len(demonstrations):]):
        cells = []
        for step, action, shown in zip(recipe.steps, parsed, demonstration.steps):
            kind = shown.before.truth.kinds[action.moved_index]
            correct = shown.before.truth.roles[action.moved_index] == step.object
            right, total = right + correct, total + 1
            cells.append(f"{step.object}: {kind} moved {action.change:.2f} m" + ("" if correct else " (WRONG)"))
        print(f"  demo {demonstration.number:2d} ({demonstration.lighting}): " + "; ".join(cells))
    return f"{right}/{total}"


def _model_summary(recipe: Recipe, grounding: RecipeGrounding) -> dict:
    summary = {}
    for name in parameter_names(recipe):
        model = grounding.object_models.get(name) or grounding.location_models[name]
        summary[name] = {"k": model.n_components_, "samples": int(model.samples_.shape[0]),
                         "means": np.round(model.means_, 3).tolist()}
    return summary


def _print_models(recipe: Recipe, grounding: RecipeGrounding) -> None:
    print("\nParameter models (GMM, k chosen by BIC over k = 1..m):")
    for name in parameter_names(recipe):
        if name in grounding.object_models:
            model = grounding.object_models[name]
            mean = model.means_[int(np.argmax(model.weights_))]
            look = f"colour ({mean[0]:.2f}, {mean[1]:.2f}, {mean[2]:.2f}), size {mean[3] * 100:.1f} x " \
                   f"{mean[4] * 100:.1f} x {mean[5] * 100:.1f} cm"
            print(f"  object   {name:15s} k={model.n_components_}  n={model.samples_.shape[0]:2d}  {look}")
        else:
            model = grounding.location_models[name]
            centres = ", ".join(f"({m[0]:.2f}, {m[1]:.2f}, {m[2]:.2f})" for m in model.means_)
            spread = np.sqrt(np.diagonal(model.covariances_[int(np.argmax(model.weights_))]))[:2]
            print(f"  location {name:15s} k={model.n_components_}  n={model.samples_.shape[0]:2d}  centre(s) "
                  f"{centres} m from the robot, spread +-{spread[0] * 100:.1f}/{spread[1] * 100:.1f} cm")


def _print_outcomes(outcomes: list[StepOutcome]) -> None:
    for outcome in outcomes:
        result = outcome.pick_place
        timing = f" [{result.sim_seconds:.1f} s simulated]" if result is not None else ""
        truth = ""
        if outcome.chosen_kind is not None:
            truth = f" (it was the {outcome.chosen_kind}; " + ("right object" if outcome.correct_object
                                                               else "WRONG object") + \
                    (", inside the true region)" if outcome.in_true_end_region else ", outside the true region)")
        print(f"  {outcome.step}: {outcome.status}{timing} - {outcome.explanation}{truth}")
    done = sum(outcome.success for outcome in outcomes)
    print(f"{done} of {len(outcomes)} steps carried out correctly.")


def _outcome_summary(outcome: StepOutcome) -> dict:
    result = outcome.pick_place
    return {"step": str(outcome.step), "status": outcome.status, "chosen_kind": outcome.chosen_kind,
            "correct_object": outcome.correct_object, "in_true_end_region": outcome.in_true_end_region,
            "sim_seconds": None if result is None else round(result.sim_seconds, 2)}
