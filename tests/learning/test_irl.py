"""Maximum-entropy IRL recovers decision-feature weights from demonstrations (thesis §7.3.2, eq. 7.5-7.7)."""

import numpy as np
import pytest
import torch

from learning.decision.weights_file import load_weights, save_weights
from learning.irl.demonstrations import DecisionTurn, QuestioningEpisode, turn_with_no_query
from learning.irl.maxent import (
    IrlConfig,
    PaddedTurns,
    _TorchTurns,
    feature_count_gap,
    fit_maxent_irl,
    split_episodes,
)
from learning.irl.policy import agreement, greedy_choice
from learning.irl.rollouts import FeatureMatchingConfig, fit_feature_matching, serial_rollouts
from learning.irl.synthetic import DT_TASK_ENV_FEATURES, SyntheticQuestioningTask, greedy_policy, softmax_policy

# a DT-task-env-like expert: wants learning progress, dislikes spending, dislikes sitting idle (the no-query
# row is at the next state, eq. 7.1, so non-query time rises when it stays quiet)
TRUE_WEIGHTS = np.array([1.0, 0.6, 0.4, 1.2, -1.5, 0.0, -0.4])
TASK = SyntheticQuestioningTask()  # budget 15, 30 turns, a scene change every 10 turns (thesis §7.4.1)
IDENTIFIABLE = np.array([name != "remaining_time" for name in DT_TASK_ENV_FEATURES])


def cosine(a, b):
    a, b = a[IDENTIFIABLE], b[IDENTIFIABLE]
    return float(a @ b / np.linalg.norm(a) / np.linalg.norm(b))


def demonstrations(policy, rng, n):
    return [TASK.episode(policy, rng, f"demo-{i}") for i in range(n)]


@pytest.fixture(scope="module")
def dt_expert():
    """Train (10 episodes, 300 turns), validation (3) and held-out test (10) episodes of a known-weights DT policy."""
    rng = np.random.default_rng(2024)
    policy = greedy_policy(TRUE_WEIGHTS)
    return demonstrations(policy, rng, 10), demonstrations(policy, rng, 3), demonstrations(policy, rng, 10)


def uniform_episode(rng, weights, n_turns):
    """Generic synthetic Phi: 7 features in [0, 1], 10-60 candidates a turn, the expert takes argmax w . Phi."""
    turns = []
    for _ in range(n_turns):
        phi = rng.uniform(0.0, 1.0, (int(rng.integers(10, 61)), len(weights)))
        turns.append(DecisionTurn(phi, int(np.argmax(phi @ weights))))
    return QuestioningEpisode(tuple(f"f{i}" for i in range(len(weights))), turns)


# -- the Done-when item: >= 95 % agreement on held-out turns ----------------------------------------------------
def test_recovers_a_known_dt_policy_on_held_out_turns(dt_expert):
    train, validation, test = dt_expert
    result = fit_maxent_irl(train, validation)
    held_out = agreement(test, result.weights.values)
    assert held_out >= 0.95, f"held-out agreement {held_out:.3f}"
    assert agreement(test, np.zeros(7)) < 0.85  # the expert is not trivially "always no query"
    assert cosine(result.weights.values, TRUE_WEIGHTS) > 0.99
    assert result.unidentified_features == ("remaining_time",)  # equal on every candidate: no choice reveals it
    assert result.weights.as_dict()["remaining_time"] == 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_recovers_random_weights_from_generic_candidate_matrices(seed):
    rng = np.random.default_rng(seed)
    weights = rng.normal(size=7)
    train, validation, test = (uniform_episode(rng, weights, n) for n in (300, 60, 300))
    result = fit_maxent_irl([train], [validation])
    assert agreement([test], result.weights.values) >= 0.95
    assert result.iterations <= 100 and result.converged


@pytest.mark.parametrize("seed", [0, 1])
def test_a_noisy_expert_reveals_the_direction_of_its_weights(seed):
    """Softmax-sampled choices, P(a|s) ~ exp(100 w . Phi): the fit finds w's direction and roughly its scale.

    A noisy expert's own choices make validation agreement a noisy yardstick, so
    the iterate is kept by validation log-likelihood here.
    """
    rng = np.random.default_rng(seed)
    policy = softmax_policy(100.0 * TRUE_WEIGHTS)
    result = fit_maxent_irl(demonstrations(policy, rng, 10), demonstrations(policy, rng, 3),
                            IrlConfig(select_by="log_likelihood"))
    assert cosine(result.weights.values, TRUE_WEIGHTS) > 0.95
    ratio = np.linalg.norm(result.weights.values) / np.linalg.norm(100.0 * TRUE_WEIGHTS)
    assert 0.5 < ratio < 2.0


# -- the objective and the optimiser ----------------------------------------------------------------------------
def test_the_likelihood_gradient_is_the_feature_count_gap_of_eq_7_7(dt_expert):
    turns = PaddedTurns(dt_expert[0])
    w = np.random.default_rng(1).normal(size=7) * 20
    v = torch.tensor(w, requires_grad=True)
    _TorchTurns(turns, np.ones(7)).mean_log_likelihood(v).backward()
    assert v.grad.numpy() == pytest.approx(feature_count_gap(turns, w), rel=1e-9, abs=1e-12)


def test_the_kept_weights_are_the_best_on_validation_and_reported_honestly(dt_expert):
    train, validation, _ = dt_expert
    result = fit_maxent_irl(train, validation, IrlConfig(max_iterations=7))
    assert result.iterations == 7 and not result.converged and len(result.history) == 8
    best = max(record.validation_agreement for record in result.history)
    assert result.validation_agreement == best == agreement(validation, result.weights.values)
    assert result.train_agreement == agreement(train, result.weights.values)
    assert result.history[result.best_iteration].validation_agreement == best
    assert set(result.summary()) == {"iterations", "seconds", "weights", "validation_agreement"}
    assert list(result.summary()["weights"]) == list(DT_TASK_ENV_FEATURES)
    assert result.weights.provenance["iterations"] == 7
    assert result.weights.provenance["best_iteration"] == result.best_iteration


def test_without_validation_the_training_set_scores(dt_expert):
    result = fit_maxent_irl(dt_expert[0])
    assert result.validation_agreement is None and result.validation_turns == 0
    assert result.train_agreement == max(record.train_agreement for record in result.history)


def test_fitting_is_deterministic(dt_expert):
    train, validation, _ = dt_expert
    first, second = (fit_maxent_irl(train, validation, IrlConfig(seed=5)) for _ in range(2))
    assert first.weights.values.tobytes() == second.weights.values.tobytes()
    assert [r.loss for r in first.history] == [r.loss for r in second.history]


def test_the_fit_leaves_the_callers_thread_settings_alone(dt_expert):
    before = torch.get_num_threads()
    fit_maxent_irl(dt_expert[0][:2], config=IrlConfig(max_iterations=2, threads=1))
    assert torch.get_num_threads() == before


def test_adam_also_learns_the_policy(dt_expert):
    train, validation, test = dt_expert
    result = fit_maxent_irl(train, validation, IrlConfig(optimizer="adam", learning_rate=0.3))
    assert result.iterations == 100
    assert agreement(test, result.weights.values) >= 0.9


def test_an_unidentifiable_weight_keeps_its_starting_value(dt_expert):
    start = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 7.0, 0.0])
    result = fit_maxent_irl(dt_expert[0], dt_expert[1], initial_weights=start)
    assert result.weights.as_dict()["remaining_time"] == 7.0


def test_learned_weights_round_trip_through_the_toml_file(dt_expert, tmp_path):
    result = fit_maxent_irl(dt_expert[0], dt_expert[1])
    path = save_weights(tmp_path / "dt-task-env.toml", result.weights, comment="test")
    loaded = load_weights(path, DT_TASK_ENV_FEATURES)
    assert loaded.values.tolist() == result.weights.values.tolist()
    assert loaded.provenance["method"] == "maxent-irl-per-turn"
    assert loaded.provenance["validation_agreement"] == pytest.approx(result.validation_agreement, abs=1e-6)


def test_padded_choices_match_the_reference_rule():
    """The vectorised argmax (ties to no query) equals ``greedy_choice`` turn by turn, including exact ties."""
    rng = np.random.default_rng(9)
    turns = []
    for _ in range(200):
        state, queries = rng.uniform(0, 1, 3), rng.integers(0, 3, (int(rng.integers(1, 6)), 3)).astype(float)
        if rng.random() < 0.3:
            queries[0] = state
        with_kinds = rng.random() < 0.8
        turns.append(turn_with_no_query(state, queries, None, ["label"] * len(queries) if with_kinds else None))
    episode = QuestioningEpisode(("a", "b", "c"), turns)
    w = np.array([1.0, 1.0, -1.0])
    padded = PaddedTurns([episode])
    assert padded.choices(w).tolist() == [greedy_choice(t, w) for t in turns]


# -- bad input ----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, message", [
    ({"max_iterations": 0}, "max_iterations must be an integer >= 1"),
    ({"max_iterations": 2.5}, "max_iterations must be an integer >= 1"),
    ({"optimizer": "sgd"}, "unknown optimizer 'sgd'; accepted: lbfgs, adam"),
    ({"l2": -1.0}, "l2 must be a finite number >= 0"),
    ({"l2": float("nan")}, "l2 must be a finite number >= 0"),
    ({"threads": 0}, "threads must be an integer >= 1"),
    ({"select_by": "accuracy"}, "unknown select_by 'accuracy'; accepted: agreement, log_likelihood"),
    ({"optimizer": "adam", "learning_rate": 0.0}, "learning_rate must be > 0"),
    ({"signs": (("budget_consumption", 2),)}, "signs must be"),
    ({"signs": (("budget_consumption", True),)}, "signs must be"),
])
def test_a_bad_config_is_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        IrlConfig(**kwargs)


def test_bad_demonstrations_are_refused(dt_expert):
    train = dt_expert[0]
    with pytest.raises(ValueError, match="no training episodes"):
        fit_maxent_irl([])
    forced = QuestioningEpisode(("a", "b"), [DecisionTurn([[0.0, 1.0]], 0, ["none"])])
    with pytest.raises(ValueError, match="no turn offers a choice"):
        fit_maxent_irl([forced])
    other = QuestioningEpisode(("a", "b"), [DecisionTurn([[0.0, 1.0], [1.0, 0.0]], 0)], "other")
    with pytest.raises(ValueError, match="must match"):
        fit_maxent_irl(train, [other])
    with pytest.raises(ValueError, match="all must match"):
        fit_maxent_irl([train[0], other])
    with pytest.raises(ValueError, match="initial_weights must be 7 finite numbers"):
        fit_maxent_irl(train, initial_weights=np.ones(3))
    with pytest.raises(ValueError, match="expected QuestioningEpisode"):
        fit_maxent_irl(["episode.json"])


def test_split_holds_out_whole_episodes_by_seed(dt_expert):
    episodes = dt_expert[0]
    train, validation = split_episodes(episodes, 3, np.random.default_rng(0))
    again = split_episodes(episodes, 3, np.random.default_rng(0))
    assert len(train) == 7 and len(validation) == 3
    assert [e.name for e in validation] == [e.name for e in again[1]]
    assert {e.name for e in train} | {e.name for e in validation} == {e.name for e in episodes}
    with pytest.raises(ValueError, match="n_validation must be in 0..9"):
        split_episodes(episodes, 10, np.random.default_rng(0))


# -- trajectory-level feature matching with rollouts (eq. 7.6, 7.7) -------------------------------------------------
def test_feature_matching_with_rollouts_learns_the_policy(dt_expert):
    train, validation, test = dt_expert

    def rollout(weights, rng):
        return TASK.episode(softmax_policy(weights), rng)

    config = FeatureMatchingConfig(max_iterations=40, rollouts_per_iteration=2, seed=3, start="zero")
    result = fit_feature_matching(train, serial_rollouts(rollout, seed=3), validation, config)
    assert result.iterations == 40 and len(result.history) == 41
    # the mechanics from w = 0 on ten episodes and 40 iterations; the recovery target is in test_irl_trajectory.py
    assert agreement(test, result.weights.values) >= 0.75 > 0.5 > agreement(test, np.zeros(7))
    assert cosine(result.weights.values, TRUE_WEIGHTS) > 0.7
    gaps = [record.loss for record in result.history[1:]]
    assert np.mean(gaps[-10:]) < 0.5 * np.mean(gaps[:5])  # the feature-count gap of eq. 7.7 closes
    assert result.weights.provenance["method"] == "maxent-irl-feature-matching"
    again = fit_feature_matching(train, serial_rollouts(rollout, seed=3), validation, config)
    assert again.weights.values.tobytes() == result.weights.values.tobytes()


def test_a_rollout_must_return_a_matching_episode(dt_expert):
    train = dt_expert[0][:2]
    with pytest.raises(ValueError, match="must return a QuestioningEpisode, got dict"):
        fit_feature_matching(train, serial_rollouts(lambda w, rng: {}), config=FeatureMatchingConfig(max_iterations=1))
    other = QuestioningEpisode(("a", "b"), [DecisionTurn([[0.0, 1.0], [1.0, 0.0]], 0)])
    with pytest.raises(ValueError, match="a rollout episode has features"):
        fit_feature_matching(train, serial_rollouts(lambda w, rng: other),
                             config=FeatureMatchingConfig(max_iterations=1))
    with pytest.raises(ValueError, match="rollouts_per_iteration must be an integer >= 1"):
        FeatureMatchingConfig(rollouts_per_iteration=0)


def test_a_failed_weights_write_keeps_the_old_file(tmp_path, monkeypatch):
    """save_weights writes beside the file and renames: a full disk mid-write leaves the old weights whole."""
    import pathlib

    from learning.decision.weights import WEIGHTS_DIRECTORY
    from learning.decision.weights_file import load_weights, save_weights

    weights = load_weights(WEIGHTS_DIRECTORY / "dt.toml")
    path = save_weights(tmp_path / "w.toml", weights)
    before = path.read_text()

    def full_disk(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pathlib.Path, "write_text", full_disk)
    with pytest.raises(OSError):
        save_weights(path, weights, comment="new")
    monkeypatch.undo()
    assert path.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.toml"]
    assert load_weights(path).feature_names == weights.feature_names


# -- issue 39: the thesis's roles of the features as sign constraints --------------------------------------------
@pytest.mark.parametrize("optimizer", ["lbfgs", "adam"])
def test_sign_constraints_hold_and_bind_where_the_data_disagree(dt_expert, optimizer):
    """The expert dislikes spending (w_bc = -1.5): asking for w_bc >= 0 pins it at 0; the free weights keep their
    signs, and the constraint the data agree with (non-query time <= 0) changes nothing's sign."""
    train, validation, _ = dt_expert
    names = DT_TASK_ENV_FEATURES
    free = fit_maxent_irl(train, validation, IrlConfig(optimizer=optimizer, learning_rate=0.3)).weights.values
    signs = (("budget_consumption", 1), ("non_query_time", -1))
    bound = fit_maxent_irl(train, validation, IrlConfig(optimizer=optimizer, learning_rate=0.3, signs=signs),
                           initial_weights=np.full(7, -1.0))
    w = dict(zip(names, bound.weights.values))
    assert free[names.index("budget_consumption")] < 0
    assert w["budget_consumption"] == 0.0
    assert w["non_query_time"] <= 0.0
    assert "budget_consumption >= 0" in bound.weights.provenance["signs"]


def test_signs_must_name_recorded_features(dt_expert):
    with pytest.raises(ValueError, match="signs name pace, which the demonstrations do not record"):
        fit_maxent_irl(dt_expert[0][:2], config=IrlConfig(signs=(("pace", 1),)))
