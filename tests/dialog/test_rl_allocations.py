"""Issue 40, item 4: a questioner trained across allocations draws each episode's allocation and sees it."""

import numpy as np
import pytest

from dialog.rl.allocations import DEFAULT_FILE, Allocation, AllocationRanges, load_allocations
from learning.errors import DataFileError, SettingsError
from learning.progress import Progress
from learning.rl.observation import ALLOCATION_NAMES, ObservationLayout, allocation_features

COSTS = {"label": 1, "demo": 2, "feature": 2, "none": 0}


def test_a_draw_is_fixed_by_its_seed_stays_in_range_and_skips_held_out_allocations():
    ranges = AllocationRanges((15, 500), (30, 150), (5, 20))
    draws = [ranges.draw(seed) for seed in range(300)]
    assert draws == [ranges.draw(seed) for seed in range(300)]  # the same seed, the same allocation
    assert all(15 <= a.budget <= 500 and 30 <= a.turns <= 150 and 5 <= a.change_every <= min(20, a.turns)
               for a in draws)
    budgets = np.array([a.budget for a in draws])
    assert 0.35 < np.mean(budgets < np.sqrt(15 * 500)) < 0.65  # log-uniform: half below the geometric mean
    narrow = AllocationRanges((15, 16), (30, 30), (5, 5), frozenset({Allocation(15.0, 30, 5)}))
    assert {narrow.draw(seed) for seed in range(50)} == {Allocation(16.0, 30, 5)}
    with pytest.raises(SettingsError, match="held-out"):
        AllocationRanges((15, 15), (30, 30), (5, 5), frozenset({Allocation(15.0, 30, 5)})).draw(0)


def test_the_shipped_file_holds_out_every_chapter_7_condition():
    ranges = load_allocations(DEFAULT_FILE)
    assert (ranges.budget, ranges.turns, ranges.change_every) == ((15, 500), (30, 150), (5, 20))
    assert Allocation(25.0, 40, 10) in ranges.held_out and Allocation(500.0, 150, 20) in ranges.held_out
    assert len(ranges.held_out) == 12  # budget {25, 500} x turns {40, 150} x a scene every {5, 10, 20}
    assert not {ranges.draw(seed) for seed in range(2000)} & ranges.held_out
    assert ranges.record()["allocations_budget"] == [15, 500]


@pytest.mark.parametrize("text, words", [
    ("[train]\nbudget = [15, 500]\nturns = [30, 150]\n", "change_every"),
    ("[train]\nbudget = [500, 15]\nturns = [30, 150]\nchange_every = [5, 20]\n", "low <= high"),
    ("[train]\nbudget = [15, 500]\nturns = [30, 150]\nchange_every = [5, 20]\nbudgets = 3\n", "unknown field"),
    ("[train]\nbudget = [15, 500]\nturns = [3, 4]\nchange_every = [5, 20]\n", "longer than its episode"),
    ("[train]\nbudget = [15, 500]\nturns = [30, 150]\nchange_every = [5, 20]\n[held_out]\nsuites = ['ch99']\n",
     "ch99"),
])
def test_a_bad_allocations_file_is_one_message_naming_the_field(tmp_path, text, words):
    path = tmp_path / "allocations.toml"
    path.write_text(text)
    with pytest.raises(DataFileError, match=words) as raised:
        load_allocations(path)
    assert "\n" not in str(raised.value)


def test_the_allocation_features_encode_budget_turns_scenes_and_questions_per_turn():
    features = allocation_features(Progress(500.0, 40, 10, COSTS))
    scale = np.log1p(1000.0)
    np.testing.assert_allclose(features, [np.log1p(500) / scale, np.log1p(40) / scale, 10 / 40, 1.0])
    assert allocation_features(Progress(25.0, 150, 10, COSTS))[3] == pytest.approx(25 / 150)
    layout = ObservationLayout(("a", "b"), 3, whatif=False, allocation=True)
    assert layout.size == ObservationLayout(("a", "b"), 3, whatif=False).size + len(ALLOCATION_NAMES)
    assert layout.record()["allocation"] is True and "allocation" not in ObservationLayout(("a",), 1).record()


def test_a_policy_file_keeps_the_allocation_layout_and_old_files_still_load(tmp_path):
    from learning.rl.policy_file import QuestionerPolicy, load_policy, save_policy

    layout = ObservationLayout(("a", "b"), 3, whatif=False, allocation=True)
    rng = np.random.default_rng(0)
    weights = (rng.normal(size=(4, layout.size)), rng.normal(size=(layout.n_actions, 4)))
    biases = (np.zeros(4), np.zeros(layout.n_actions))
    save_policy(tmp_path / "q.toml", QuestionerPolicy(layout, weights, biases, "tanh", {"seed": 0}))
    assert load_policy(tmp_path / "q.toml").layout == layout
    shipped = load_policy("learning/rl/policies/questioner-ch7-training.toml")
    assert shipped.layout.allocation is False
    text = (tmp_path / "q.toml").read_text().replace('"log_budget", ', "")
    (tmp_path / "q.toml").write_text(text)
    with pytest.raises(DataFileError, match="allocation_features must be"):
        load_policy(tmp_path / "q.toml")


gym = pytest.importorskip("gymnasium", reason="the rl extra (pip install -e '.[rl]') installs gymnasium")


def test_each_episode_plays_its_own_allocation_and_observes_it():
    from dialog.rl.gym_env import QuestioningEnv

    env = QuestioningEnv(allocations={"budget": [2, 6], "turns": [3, 5], "change_every": [1, 3]}, datasets=1)
    assert env.observation_space.shape == (env.layout.size,) and env.layout.allocation
    seen = set()
    for seed in range(4):
        obs, info = env.reset(seed=seed)
        allocation = info["allocation"]
        assert allocation == env.allocations.draw(seed).record()
        assert env.manager.state.budget == allocation["budget"] and env.manager.config.turns == allocation["turns"]
        np.testing.assert_allclose(obs[-len(ALLOCATION_NAMES):],
                                   allocation_features(env.manager.state.progress).astype(np.float32))
        steps, done = 0, False
        while not done:
            obs, _, done, _, info = env.step(0)
            steps += 1
        assert steps == allocation["turns"]
        seen.add(tuple(allocation.values()))
    assert len(seen) > 1
    with pytest.raises(SettingsError, match="not both"):
        QuestioningEnv(allocations={"budget": [2, 6], "turns": [3, 5], "change_every": [1, 3]}, budget=4.0)
    with pytest.raises(SettingsError, match="keys budget, turns, change_every"):
        QuestioningEnv(allocations={"budget": [2, 6]})


def test_train_questioner_refuses_allocations_with_a_fixed_budget_in_one_line(tmp_path, capsys):
    from dialog.cli import main

    assert main(["train-questioner", "--out", str(tmp_path / "q.toml"), "--allocations", "--budget", "9"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--allocations" in err and "--budget" in err
