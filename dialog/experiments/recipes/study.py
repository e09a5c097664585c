"""The chapter-4 experiments: ground recipes from scripted demonstrations and test the groundings.

One implementation, used by ``scripts/recipe_experiments.py`` and by the
``recipes`` kind of ``teachbot regress`` (``dialog/experiments/recipes/suite.py``):

* within-kitchen cross-validation (thesis §4.4.1, figure 4.6): for m training
  demonstrations drawn uniformly at random, learn every parameter model and
  test each one on the n - m held-out demonstrations (§4.3.4);
* varied pairs (§4.4.1, figure 4.7): every pair of demonstrations as a training
  set, with its environment edit distance (eq. 4.4);
* between-kitchen transfer (§4.4.2, figure 4.8): m demonstrations from *each*
  kitchen of a training set make one aggregate model, tested on the test
  kitchen's demonstrations not used for training;
* execution (§4.2.4): the grounding from all demonstrations carries the recipe
  out with the Panda in fresh arrangements (a real pick-place per step).

Each ``*_runs`` function returns one row per trained grounding with its
accuracy per parameter; the script's summaries (``cross_validation``,
``varied_pairs``, ``transfer``) average those rows.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from bullet_world.recipes.tracking import match_rows
from bullet_world.recipes.world import RecipeDemonstration, RecipeWorld
from dialog.recipe_session import (
    evaluate_demonstration,
    execute_recipe,
    ground,
    parameter_names,
    recipe_steps,
)
from learning.errors import SettingsError
from learning.recipes.format import Recipe
from learning.recipes.grounding import DEFAULT_TAU
from robot import Arm
from robot.pick_place import Manipulator


def demonstration_rng(seed: int) -> np.random.Generator:
    """The scripted teacher's generator for a world built with ``seed``."""
    return np.random.default_rng([seed, 11])


def collect(recipe: Recipe, task: str, kitchen: str, count: int, seed: int) -> list[RecipeDemonstration]:
    """``count`` scripted demonstrations of ``recipe`` in ``kitchen`` (camera + perception, no arm)."""
    with RecipeWorld(recipe_steps(recipe), task=task, kitchen=kitchen, seed=seed) as world:
        return world.demonstrate(count, demonstration_rng(seed))


def accuracy(recipe: Recipe, train: list[RecipeDemonstration], test: list[RecipeDemonstration],
             rng: np.random.Generator) -> dict[str, float]:
    """Fraction of successful trials per parameter when trained on ``train`` and tested on ``test`` (§4.3.4)."""
    grounding = ground(recipe, train, rng)
    trials: dict[str, list[bool]] = {name: [] for name in parameter_names(recipe)}
    for demonstration in test:
        for name, results in evaluate_demonstration(grounding, recipe, demonstration).items():
            trials[name].extend(results)
    return {name: float(np.mean(results)) for name, results in trials.items()}


def cross_validation_runs(recipe: Recipe, demos: list[RecipeDemonstration], m_values: Sequence[int],
                          repeats: int, rng: np.random.Generator) -> list[dict]:
    """``repeats`` random training sets of every size m, each tested on the held-out rest (figure 4.6)."""
    n = len(demos)
    bad = [m for m in m_values if not 1 <= m < n]
    if bad:
        raise SettingsError(f"cross-validation needs 1 <= m < n = {n} demonstrations, got m = {bad}")
    runs = []
    for m in m_values:
        for repeat in range(repeats):
            chosen = set(rng.choice(n, size=m, replace=False).tolist())
            train = [demos[i] for i in sorted(chosen)]
            test = [demos[i] for i in range(n) if i not in chosen]
            runs.append({"m": int(m), "repeat": repeat, "train": sorted(chosen),
                         "accuracy": accuracy(recipe, train, test, rng)})
    return runs


def cross_validation(recipe: Recipe, demos: list[RecipeDemonstration], repeats: int,
                     rng: np.random.Generator) -> dict[str, list[float]]:
    """Mean accuracy per parameter for m = 1..n-1 training demonstrations (figure 4.6)."""
    runs = cross_validation_runs(recipe, demos, range(1, len(demos)), repeats, rng)
    return {name: [float(np.mean([r["accuracy"][name] for r in runs if r["m"] == m]))
                   for m in range(1, len(demos))] for name in parameter_names(recipe)}


def edit_distance(first: RecipeDemonstration, second: RecipeDemonstration) -> float:
    """Environment edit distance of two demonstrations (eq. 4.4), over their initial states.

    Eq. 4.4 sums dist (eq. 4.1) over every pair of objects; here each object is paired with itself
    (rows matched by ``recipe_tracking``), so objects that stay put add nothing.
    """
    a, b = first.steps[0].before, second.steps[0].before
    order = match_rows(a.appearance, a.locations, b.appearance, b.locations)
    return float(np.sum(np.linalg.norm(b.locations[order] - a.locations, axis=1)))


def pair_runs(recipe: Recipe, demos: list[RecipeDemonstration], rng: np.random.Generator) -> list[dict]:
    """Every pair of demonstrations as a training set (m = 2), tested on the rest, with its edit distance."""
    runs = []
    for i, j in itertools.combinations(range(len(demos)), 2):
        test = [d for k, d in enumerate(demos) if k not in (i, j)]
        result = accuracy(recipe, [demos[i], demos[j]], test, rng)
        runs.append({"pair": (i, j), "distance_m": edit_distance(demos[i], demos[j]), "accuracy": result,
                     "lightings": len({demos[i].lighting, demos[j].lighting})})
    return runs


def varied_thirds(runs: list[dict]) -> tuple[list[dict], list[dict]]:
    """The third of pairs with the smallest and the third with the largest edit distance (ties by accuracy)."""
    ordered = sorted(runs, key=lambda run: (run["distance_m"], _mean(run)))
    third = max(1, len(ordered) // 3)
    return ordered[:third], ordered[-third:]


def varied_pairs(recipe: Recipe, demos: list[RecipeDemonstration], rng: np.random.Generator) -> dict:
    """Mean accuracy of the most and of the least varied third of all pairs (thesis §4.4.1, figure 4.7)."""
    runs = pair_runs(recipe, demos, rng)
    least, most = varied_thirds(runs)
    return {"pairs": len(runs), "least_varied_accuracy": float(np.mean([_mean(r) for r in least])),
            "most_varied_accuracy": float(np.mean([_mean(r) for r in most])),
            "least_varied_distance_m": float(np.mean([r["distance_m"] for r in least])),
            "most_varied_distance_m": float(np.mean([r["distance_m"] for r in most]))}


def transfer_runs(recipe: Recipe, demos: dict[str, list[RecipeDemonstration]], m_values: Sequence[int],
                  repeats: int, rng: np.random.Generator, test_kitchens: Sequence[str] | None = None) -> list[dict]:
    """Every non-empty set of training kitchens, m demonstrations from each, tested in every test kitchen
    on its demonstrations not used for training (figure 4.8); one row per repetition."""
    kitchens = list(demos)
    tested = kitchens if test_kitchens is None else [k for k in kitchens if k in test_kitchens]
    runs = []
    for m in m_values:
        for size in range(1, len(kitchens) + 1):
            for training in itertools.combinations(kitchens, size):
                for test_kitchen in tested:
                    for repeat in range(repeats):
                        train, used = [], {}
                        for kitchen in training:
                            chosen = sorted(rng.choice(len(demos[kitchen]), size=m, replace=False).tolist())
                            used[kitchen] = set(chosen)
                            train.extend(demos[kitchen][i] for i in chosen)
                        held_out = used.get(test_kitchen, set())
                        test = [d for i, d in enumerate(demos[test_kitchen]) if i not in held_out]
                        runs.append({"m": int(m), "train": list(training), "test": test_kitchen,
                                     "situated": test_kitchen in training, "repeat": repeat,
                                     "accuracy": accuracy(recipe, train, test, rng)})
    return runs


def transfer(recipe: Recipe, demos: dict[str, list[RecipeDemonstration]], m_values: list[int], repeats: int,
             rng: np.random.Generator) -> list[dict]:
    """Mean accuracy per parameter for every (m, training kitchens, test kitchen) (figure 4.8)."""
    runs = transfer_runs(recipe, demos, m_values, repeats, rng)
    rows = []
    for _, group in itertools.groupby(runs, key=lambda r: (r["m"], tuple(r["train"]), r["test"])):
        group = list(group)
        mean = {name: float(np.mean([r["accuracy"][name] for r in group])) for name in group[0]["accuracy"]}
        first = group[0]
        rows.append({"m": first["m"], "train": first["train"], "test": first["test"],
                     "situated": first["situated"], "accuracy": mean, "mean": float(np.mean(list(mean.values())))})
    return rows


def execution_runs(recipe: Recipe, world: RecipeWorld, demos: list[RecipeDemonstration], trials: int,
                   rng: np.random.Generator, grasp: str = "friction", tau: float = DEFAULT_TAU) -> list[dict]:
    """Ground on ``demos``, then carry the recipe out ``trials`` times in fresh arrangements, the lighting
    conditions taking turns (§4.2.4 and a real pick-place per step). Failures are rows, never exceptions."""
    grounding = ground(recipe, demos, rng)
    lightings = list(world.setup.lighting)
    manipulator = Manipulator(Arm(world.world), grasp)
    runs = []
    try:
        for trial in range(trials):
            world.set_lighting(lightings[trial % len(lightings)])
            world.arrange(world.new_arrangement(rng))
            outcomes = execute_recipe(grounding, recipe, world, manipulator, rng, tau)
            runs.append({"trial": trial, "lighting": world.lighting_name, "m": len(demos),
                         "steps": [{"step": str(o.step), "status": o.status, "chosen_kind": o.chosen_kind,
                                    "correct_object": o.correct_object, "in_true_end_region": o.in_true_end_region,
                                    "success": o.success} for o in outcomes],
                         "success_rate": float(np.mean([o.success for o in outcomes]))})
    finally:
        manipulator.close()
    return runs


def _mean(run: dict) -> float:
    return float(np.mean(list(run["accuracy"].values())))
