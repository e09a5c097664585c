"""Shared fixtures: one real PyBullet kitchen with the arm, reused by the simulator tests."""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def kitchen():
    from dialog.environment import SimulatedKitchen

    env = SimulatedKitchen(seed=3)
    yield env
    env.close()


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
