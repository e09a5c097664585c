"""Shared fixtures: one real PyBullet kitchen with the arm, reused by the simulator tests."""

import os

import numpy as np
import pytest


def pytest_sessionstart(session):
    """CI sets TEACHBOT_REQUIRE_BROWSER so that the headless-Chromium tests run rather than skip."""
    from bullet_world.viewer.snapshot import find_chromium

    if os.environ.get("TEACHBOT_REQUIRE_BROWSER") and find_chromium() is None:
        raise pytest.UsageError("TEACHBOT_REQUIRE_BROWSER is set but no Chromium is installed at /usr/bin/chromium; "
                                "install it with apt-get install -y chromium")


@pytest.fixture(scope="module")
def kitchen():
    from dialog.environment import SimulatedKitchen

    env = SimulatedKitchen(seed=3)
    yield env
    env.close()


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
