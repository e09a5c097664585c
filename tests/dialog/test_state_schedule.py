"""When a prepare-lunch object is in which state (docs/open-settings.md): on the episode's clock, or drawn at
random at every new scene, as the thesis's §6.5.3 samples."""

import numpy as np
import pytest

from dialog.experiments.pools import PoolEnvironment, load_pools, state_order
from dialog.experiments.suite import SuiteError, load_suite
from learning.errors import SettingsError


@pytest.fixture(scope="module")
def pools():
    return load_pools("prepare-lunch", "kitchen-1", 1)


def first_scene_states(pools, schedule, draws=40):
    seen = set()
    for seed in range(draws):
        world = PoolEnvironment(pools.train[0], pools.test, pools.task, 3, state_schedule=schedule)
        seen |= set(world.next_scene(np.random.default_rng(seed)).truth.states)
    return seen


def test_the_clock_shows_only_first_states_early_and_per_scene_shows_them_all(pools):
    order = state_order(pools.task)
    assert order, "prepare-lunch has kinds with ordered states"
    later = {state for states in order.values() for state in states[1:]}
    assert not first_scene_states(pools, "episode-clock") & later
    assert first_scene_states(pools, "per-scene") & later


def test_both_schedules_draw_as_many_numbers_from_the_generator(pools):
    worlds = [PoolEnvironment(pools.train[0], pools.test, pools.task, 3, state_schedule=s)
              for s in ("episode-clock", "per-scene")]
    rngs = [np.random.default_rng(5), np.random.default_rng(5)]
    for world, rng in zip(worlds, rngs):
        world.next_scene(rng)
    assert rngs[0].integers(1 << 30) == rngs[1].integers(1 << 30)


def test_a_bad_schedule_is_one_line_naming_the_accepted(pools, tmp_path):
    with pytest.raises(SettingsError, match="choose one of episode-clock, per-scene"):
        PoolEnvironment(pools.train[0], pools.test, pools.task, 3, state_schedule="weekly")
    suite = tmp_path / "s.toml"
    suite.write_text('name = "s"\nstrategies = ["passive"]\ncheckpoints = [2]\nstate_schedule = "weekly"\n'
                     '[[condition]]\nname = "c"\nbudget = 3\nturns = 3\nchange_every = 1\n')
    with pytest.raises(SuiteError, match="state_schedule 'weekly' is not one of episode-clock, per-scene"):
        load_suite(str(suite))


def test_a_condition_may_override_the_suites_schedule(tmp_path):
    suite = tmp_path / "s.toml"
    suite.write_text('name = "s"\nstrategies = ["passive"]\ncheckpoints = [2]\nstate_schedule = "per-scene"\n'
                     '[[condition]]\nname = "a"\nbudget = 3\nturns = 3\nchange_every = 1\n'
                     '[[condition]]\nname = "b"\nbudget = 3\nturns = 3\nchange_every = 1\n'
                     'state_schedule = "episode-clock"\n')
    assert [c.state_schedule for c in load_suite(str(suite)).conditions] == ["per-scene", "episode-clock"]
