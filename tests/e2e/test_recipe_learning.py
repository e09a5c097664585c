"""Grounding recipes from demonstrations in PyBullet: learning curves rise, models do not transfer (thesis ch. 4)."""

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from bullet_world.recipes.world import RecipeWorld
from dialog.recipe_session import (
    action_observations,
    evaluate_demonstration,
    ground,
    parameter_names,
    recipe_steps,
)
from learning.recipes.format import load_builtin_recipe

pytestmark = pytest.mark.e2e


@pytest.fixture(autouse=True)
def one_blas_thread():
    """Tiny matrices: a multi-threaded BLAS only spins on a shared machine."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def accuracy(recipe, grounding, demos):
    trials = {name: [] for name in parameter_names(recipe)}
    for demo in demos:
        for name, results in evaluate_demonstration(grounding, recipe, demo).items():
            trials[name].extend(results)
    return {name: float(np.mean(values)) for name, values in trials.items()}


def test_more_demonstrations_ground_every_pasta_parameter():
    pasta = load_builtin_recipe("serve-pasta")
    with RecipeWorld(recipe_steps(pasta), task="serve-pasta", kitchen="kitchen-1", seed=0) as world:
        demos = world.demonstrate(12, np.random.default_rng(0))
    assert all(len(observations) == 3 for observations in map(action_observations, demos))
    train = [demos[i] for i in (0, 2, 4, 7, 9, 11)]  # both lighting conditions, spread over the sweep
    test = [demo for demo in demos if demo not in train]
    many = accuracy(pasta, ground(pasta, train, np.random.default_rng(1)), test)
    one = accuracy(pasta, ground(pasta, demos[:1], np.random.default_rng(1)), demos[1:])
    assert min(many.values()) >= 0.8, many
    assert np.mean(list(many.values())) > np.mean(list(one.values())) + 0.2, (many, one)


def test_models_from_another_kitchen_fail_in_this_one():
    salad = load_builtin_recipe("serve-salad")
    demos = {}
    for kitchen in ("kitchen-1", "kitchen-2"):
        with RecipeWorld(recipe_steps(salad), task="serve-salad", kitchen=kitchen, seed=0) as world:
            demos[kitchen] = world.demonstrate(6, np.random.default_rng(0))
    test = demos["kitchen-1"][1::2]
    here = accuracy(salad, ground(salad, demos["kitchen-1"][::2], np.random.default_rng(2)), test)
    elsewhere = accuracy(salad, ground(salad, demos["kitchen-2"][::2], np.random.default_rng(2)), test)
    assert np.mean(list(here.values())) >= 0.8, here
    assert np.mean(list(elsewhere.values())) <= 0.4, elsewhere
