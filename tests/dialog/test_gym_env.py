"""teachbot/Questioning-v0: Gymnasium's checker, masked random play, determinism by seed, vector environments."""

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium", reason="the rl extra (pip install -e '.[rl]') installs gymnasium")

from dialog.rl.gym_env import ENV_ID, QuestioningEnv  # noqa: E402
from learning.errors import SettingsError  # noqa: E402

SMALL = {"turns": 8, "budget": 8.0, "change_every": 4}  # the training condition's task and data, shorter


def play(env, seed, policy_seed=0):
    """A masked random policy for one whole episode: (observations, actions, rewards, last info)."""
    rng = np.random.default_rng(policy_seed)
    obs, info = env.reset(seed=seed)
    observations, actions, rewards, done = [obs], [], [], False
    while not done:
        action = int(rng.choice(np.flatnonzero(info["action_mask"])))
        obs, reward, done, truncated, info = env.step(action)
        assert not truncated
        observations.append(obs)
        actions.append(action)
        rewards.append(reward)
    return observations, actions, rewards, info


def test_gymnasium_env_checker_passes():
    from gymnasium.utils.env_checker import check_env

    assert ENV_ID in gym.registry
    env = gym.make(ENV_ID, **SMALL, render_mode="ansi").unwrapped
    check_env(env, skip_render_check=False)
    assert env.layout.n_actions == 2 + 4 + 12  # no query, the feature query, 4 concepts, 12 scene objects
    env.reset(seed=0)
    env.step(0)
    assert env.render().startswith("turn 1: none")


def test_a_masked_random_policy_plays_whole_episodes():
    env = QuestioningEnv(**SMALL)
    for seed in (0, 1):
        observations, actions, rewards, info = play(env, seed)
        assert len(actions) == SMALL["turns"] and info["turn"] == SMALL["turns"]
        assert all(env.observation_space.contains(o) for o in observations)
        assert not info["invalid_action"] and info["spent"] <= SMALL["budget"]
        kinds = [r["action"]["kind"] for r in env.records[1:]]
        assert kinds.count("none") < len(kinds)  # it asked something
        initial = env.records[1]["accuracy"] - rewards[0]
        assert sum(rewards) == pytest.approx(info["accuracy"] - initial)  # reward: accuracy gained, turn by turn
        with pytest.raises(SettingsError, match="call reset"):
            env.step(0)


def test_the_same_seed_gives_the_same_episode():
    first, second = QuestioningEnv(**SMALL), QuestioningEnv(**SMALL)
    a, b = play(first, 5), play(second, 5)
    np.testing.assert_array_equal(np.array(a[0]), np.array(b[0]))
    assert a[1] == b[1] and a[2] == b[2]
    assert [r.get("question") for r in first.records] == [r.get("question") for r in second.records]
    other = play(second, 6)
    assert not np.array_equal(np.array(a[0][0]), np.array(other[0][0]))  # another seed, another first scene


def test_a_masked_slot_is_played_as_no_query_and_flagged():
    env = QuestioningEnv(**SMALL)
    obs, info = env.reset(seed=2)
    env.step(1)  # the feature query: afterwards it is masked
    mask = env.action_masks()
    assert not mask[1] and mask[0]
    _, _, _, _, info = env.step(1)
    assert info["invalid_action"] and env.records[-1]["action"]["kind"] == "none"
    with pytest.raises(SettingsError, match="is not a slot"):
        env.step(env.layout.n_actions)


def test_options_price_and_no_whatif():
    plain = QuestioningEnv(**SMALL, whatif=False)
    assert plain.observation_space.shape == (7 + plain.layout.n_actions,)
    priced = QuestioningEnv(**SMALL, price=0.05)
    free = QuestioningEnv(**SMALL)
    for env in (priced, free):
        env.reset(seed=3)
    _, cheap, *_ = free.step(2)  # the same demonstration query in the same episode
    _, paid, *_ = priced.step(2)
    assert paid == pytest.approx(cheap - 0.05 * free.records[-1]["cost"])
    with pytest.raises(SettingsError, match="price must be"):
        QuestioningEnv(**SMALL, price=-1)
    with pytest.raises(SettingsError, match="turns must be at least 1"):
        QuestioningEnv(turns=0)


def test_async_vector_envs_step_and_agree_with_a_single_env():
    from gymnasium.vector import AsyncVectorEnv

    vector = AsyncVectorEnv([lambda: QuestioningEnv(**SMALL)] * 2, context="spawn")
    try:
        obs, infos = vector.reset(seed=[11, 12])
        assert obs.shape == (2, vector.single_observation_space.shape[0])
        single = QuestioningEnv(**SMALL)
        single_obs, single_info = single.reset(seed=11)
        np.testing.assert_array_equal(obs[0], single_obs)
        for _ in range(3):
            actions = np.array([int(np.flatnonzero(mask)[-1]) for mask in infos["action_mask"]])
            obs, rewards, done, _, infos = vector.step(actions)
            single_obs, single_reward, *_ = single.step(int(actions[0]))
            np.testing.assert_array_equal(obs[0], single_obs)
            assert rewards[0] == pytest.approx(single_reward)
    finally:
        vector.close()


# -- issue 24: Gymnasium's conventions; every argument checked, none ignored --------------------------------
@pytest.mark.parametrize("action", [1.7, "0", True, np.bool_(True), np.float64(1.0), np.array([1]), None])
def test_an_action_outside_the_action_space_raises_as_gymnasium_envs_do(action):
    from dialog.rl.gym_env import InvalidActionError

    env = QuestioningEnv(**SMALL)
    env.reset(seed=0)
    assert not (env.action_space.contains(action) and not isinstance(action, bool | np.bool_))
    with pytest.raises(AssertionError, match="is not a slot") as raised:
        env.step(action)
    assert isinstance(raised.value, InvalidActionError) and isinstance(raised.value, SettingsError)
    assert env.records[-1].get("turn") is None  # nothing was played
    env.step(np.int64(0))
    env.step(np.array(0))  # a 0-d integer array is in Discrete, as Gymnasium says
    assert env.manager.turn == 2


@pytest.mark.parametrize("kwargs, message", [
    ({"datasets": -3}, "datasets must be a whole number of 1 or more, got -3"),
    ({"datasets": 10**6}, "datasets: 1000000 is beyond the limit of 100"),
    ({"datasets": 2.0}, "datasets must be a whole number"),
    ({"whatif": "no"}, "whatif must be True or False .*got 'no'"),
    ({"budget": "10"}, r"budget must be a number of zero or more cost units, got '10' \(a str\)"),
    ({"data_seed": -1}, "data_seed must be a whole number of 0 or more"),
    ({"teacher": "oracle"}, "teacher must be a dict"),
    ({"teacher": {"mislabel_rate": 2}}, "'mislabel_rate' must be >= 0 and <= 1"),
    ({"turns": 10**8}, "turns: 100000000 is beyond the limit of 10000"),
    ({"transcript": 3}, "transcript must be None or a path"),
    ({"objects_per_scene": 0}, r"objects_per_scene must be None or a whole number from 1 to \d+ .*got 0"),
    ({"objects_per_scene": 10**6}, r"objects_per_scene must be .*\(the largest scene of task 'prepare-lunch'\)"),
    ({"objects_per_scene": 6.0}, "objects_per_scene must be None or a whole number"),
])
def test_bad_settings_are_refused_with_what_is_wrong(kwargs, message):
    from learning.errors import TeachbotError

    with pytest.raises(TeachbotError, match=message):
        gym.make(ENV_ID, **{**SMALL, **kwargs})


@pytest.mark.parametrize("options, message", [
    ({"budget": 3}, "reset options must be a dict with the keys dataset"), ("fast", "reset options must be a dict"),
    ({"dataset": 5}, r"'dataset' must be a whole number 0\.\.4"), ({"dataset": True}, "'dataset' must be"),
])
def test_reset_options_are_validated_not_ignored(options, message):
    env = QuestioningEnv(**SMALL)
    with pytest.raises(SettingsError, match=message):
        env.reset(seed=0, options=options)
    with pytest.raises(SettingsError, match="seed must be None or a whole number"):
        env.reset(seed=-1)
    env.reset(seed=7, options={"dataset": 3})
    assert env.records[0]["session"]["dataset"] == 3  # not 7 mod 5
    env.reset(seed=7, options={})
    assert env.records[0]["session"]["dataset"] == 2


def test_objects_per_scene_sizes_the_scenes_the_label_slots_and_the_data_plan(monkeypatch):
    import dialog.rl.gym_env as gym_env

    asked = []
    real = gym_env.load_pools

    def recording(*args, plan_options=(), **kwargs):  # the task's own data, so nothing new is rendered
        asked.append(plan_options)
        return real(*args, **kwargs)

    monkeypatch.setattr(gym_env, "load_pools", recording)
    env = QuestioningEnv(**SMALL, objects_per_scene=6)
    assert asked == [(("objects_per_scene", 6),)]  # the data set is the one a suite with 6 objects renders
    assert env.layout.n_actions == 2 + 4 + 6 and env.objects_per_scene == 6
    _, info = env.reset(seed=0)
    assert env.manager.scene.n_objects == 6
    assert info["action_mask"].shape == (env.layout.n_actions,)
