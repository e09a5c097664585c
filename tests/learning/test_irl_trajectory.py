"""Trajectory-level MaxEnt IRL (thesis eq. 7.7): recovery on a synthetic task, selection, the rollout estimators."""

import numpy as np
import pytest

from learning.irl.demonstrations import QuestioningEpisode
from learning.irl.policy import agreement, policy_probabilities
from learning.irl.rollouts import (
    FeatureMatchingConfig,
    fit_feature_matching,
    mean_expected_feature_counts,
    mean_feature_counts,
    rollout_generator,
    serial_rollouts,
)
from learning.irl.synthetic import SyntheticQuestioningTask, greedy_policy, softmax_policy
from learning.strategies.maxent_policy import MaxEntPolicyStrategy

# a DT-task-env-like expert (the no-query row at the next state, eq. 7.1): wants learning progress, dislikes
# spending and sitting idle
TRUE_WEIGHTS = np.array([1.0, 0.6, 0.4, 1.2, -1.5, 0.0, -0.4])
TASK = SyntheticQuestioningTask()  # budget 15, 30 turns, a scene change every 10 turns (thesis §7.4.1)


def learner_rollout(weights, rng):
    return TASK.episode(softmax_policy(weights), rng)


@pytest.fixture(scope="module")
def expert():
    """Three training episodes (as the thesis), three validation and ten held-out test episodes of a known DT."""
    rng = np.random.default_rng(2024)
    policy = greedy_policy(TRUE_WEIGHTS)
    return [[TASK.episode(policy, rng, f"demo-{i}") for i in range(n)] for n in (3, 3, 10)]


def test_trajectory_irl_recovers_known_weights_on_held_out_synthetic_episodes(expert):
    """Three expert episodes, as the thesis; the default start is the per-turn MaxEnt fit (docs/irl.md: the sweep)."""
    train, validation, test = expert
    config = FeatureMatchingConfig(max_iterations=100, rollouts_per_iteration=4, seed=0)
    result = fit_feature_matching(train, serial_rollouts(learner_rollout, seed=0), validation, config)
    held_out = agreement(test, result.weights.values)
    assert held_out >= 0.9, f"held-out agreement {held_out:.3f}"  # measured 0.958; 25 fits: 0.916-0.987
    assert agreement(test, np.zeros(7)) < 0.5  # the expert is not "always stay quiet"
    assert result.weights.provenance["learner_counts"] == "expected under the policy"
    assert result.weights.provenance["start"].startswith("per-turn MaxEnt fit (softmax")
    assert len(result.history) == 101  # iteration 0 (the start) and 100 rollout iterations


def test_the_start_of_the_ascent(expert):
    """start="zero" is the earlier default (w = 0); given initial weights win over either start."""
    train, validation, _ = expert
    zero = fit_feature_matching(train, serial_rollouts(learner_rollout), validation,
                                FeatureMatchingConfig(max_iterations=1, rollouts_per_iteration=1, start="zero",
                                                      select="accuracy"),
                                evaluate=lambda w: -float(np.abs(w).sum()))  # keeps iteration 0
    assert zero.best_iteration == 0 and not np.any(zero.weights.values)
    assert zero.weights.provenance["start"] == "zero"
    given = fit_feature_matching(train, serial_rollouts(learner_rollout), validation,
                                 FeatureMatchingConfig(max_iterations=1, rollouts_per_iteration=1, select="accuracy"),
                                 initial_weights=TRUE_WEIGHTS,
                                 evaluate=lambda w: -float(np.abs(w - TRUE_WEIGHTS).sum()))
    assert given.weights.provenance["start"] == "given"
    np.testing.assert_array_equal(given.weights.values, TRUE_WEIGHTS)
    with pytest.raises(ValueError, match="start must be one of per-turn, zero"):
        FeatureMatchingConfig(start="random")


def test_the_evaluated_iterate_with_the_best_score_is_kept(expert):
    train, validation, _ = expert
    scores = iter([0.1, 0.5, 0.9, 0.3, 0.8, 0.2])  # iterations 0, 2, 4, 6, 8 and the last (9)
    calls = []

    def evaluate(weights):
        calls.append(weights.copy())
        return next(scores)

    config = FeatureMatchingConfig(max_iterations=9, rollouts_per_iteration=1, seed=1, evaluate_every=2,
                                   select="accuracy")
    result = fit_feature_matching(train, serial_rollouts(learner_rollout, seed=1), validation, config,
                                  evaluate=evaluate)
    evaluated = [record.iteration for record in result.history if record.evaluation is not None]
    assert evaluated == [0, 2, 4, 6, 8, 9] and len(calls) == 6
    assert result.best_iteration == 4  # the best score, not the last iterate
    np.testing.assert_array_equal(result.weights.values, calls[2])
    assert result.weights.provenance["select_by"] == "evaluation"
    seen = []
    fit_feature_matching(train, serial_rollouts(learner_rollout, seed=1), validation,
                         FeatureMatchingConfig(max_iterations=2, rollouts_per_iteration=1, select="accuracy"),
                         evaluate=lambda w: 0.5, progress=lambda record, seconds: seen.append(record.iteration))
    assert seen == [0, 1, 2]
    with pytest.raises(ValueError, match="the evaluation of iteration 0 returned nan"):
        fit_feature_matching(train, serial_rollouts(learner_rollout), validation,
                             FeatureMatchingConfig(max_iterations=1, rollouts_per_iteration=1, select="accuracy"),
                             evaluate=lambda w: float("nan"))


def test_selection_by_likelihood_or_agreement_scores_only_the_kept_iterate(expert):
    """select="log_likelihood" keeps the iterate with the best held-out log-likelihood (eq. 7.5); evaluate(w) then
    runs once, on the kept weights, for the record. "accuracy" without evaluate is refused."""
    from learning.irl.maxent import PaddedTurns, log_likelihood

    train, validation, _ = expert
    held_out = PaddedTurns(validation, "validation")
    calls, iterates = [], []
    config = FeatureMatchingConfig(max_iterations=6, rollouts_per_iteration=1, seed=1, start="zero",
                                   select="log_likelihood")
    result = fit_feature_matching(train, serial_rollouts(learner_rollout, seed=1), validation, config,
                                  evaluate=lambda w: calls.append(w.copy()) or 0.25)
    assert len(calls) == 1 and result.weights.provenance["select_by"] == "log_likelihood"
    np.testing.assert_array_equal(calls[0], result.weights.values)
    assert [record.evaluation for record in result.history].count(0.25) == 1
    assert result.history[result.best_iteration].evaluation == 0.25
    again = fit_feature_matching(train, serial_rollouts(learner_rollout, seed=1), validation, config,
                                 progress=lambda record, seconds: iterates.append(record.iteration))
    assert iterates == list(range(7)) and again.weights.values.tobytes() == result.weights.values.tobytes()
    assert log_likelihood(held_out, result.weights.values) == pytest.approx(result.validation_log_likelihood)
    by_agreement = fit_feature_matching(train, serial_rollouts(learner_rollout, seed=1), validation,
                                        FeatureMatchingConfig(max_iterations=6, rollouts_per_iteration=1, seed=1,
                                                              start="zero"))
    assert by_agreement.weights.provenance["select_by"] == "agreement"
    assert held_out.agreement(by_agreement.weights.values) >= held_out.agreement(result.weights.values)
    with pytest.raises(ValueError, match="select='accuracy' scores iterates by task accuracy: pass evaluate"):
        fit_feature_matching(train, serial_rollouts(learner_rollout), validation,
                             FeatureMatchingConfig(max_iterations=1, rollouts_per_iteration=1, select="accuracy"))
    with pytest.raises(ValueError, match="select must be one of agreement, log_likelihood, accuracy"):
        FeatureMatchingConfig(select="best")


def test_serial_rollouts_are_deterministic_by_seed_and_iteration():
    weights = TRUE_WEIGHTS * 20
    first = serial_rollouts(learner_rollout, seed=5)(weights, 3, 2)
    again = serial_rollouts(learner_rollout, seed=5)(weights, 3, 2)
    other = serial_rollouts(learner_rollout, seed=6)(weights, 3, 2)

    def choices(episodes):
        return [[turn.chosen for turn in episode.turns] for episode in episodes]

    assert choices(first) == choices(again) != choices(other)
    assert choices(first)[0] != choices(first)[1]  # each rollout of an iteration has its own generator
    assert rollout_generator(5, 3, 1).random() == rollout_generator(5, 3, 1).random()


def test_expected_counts_are_the_sampled_counts_averaged_over_the_policy(expert):
    """The learner's counts of eq. 7.7 at the visited states: sum_a P(a|s) Phi[a] is what sampling gives on average."""
    episode = expert[0][0]
    weights = TRUE_WEIGHTS * 30
    rng = np.random.default_rng(0)
    sampled = []
    for _ in range(2000):
        turns = [type(turn)(turn.phi, int(rng.choice(turn.n_actions, p=policy_probabilities(turn.phi, weights))),
                            turn.kinds) for turn in episode.turns]
        sampled.append(mean_feature_counts([QuestioningEpisode(episode.feature_names, turns)]))
    expected = mean_expected_feature_counts([episode], weights)
    np.testing.assert_allclose(np.mean(sampled, axis=0), expected, atol=5e-3)
    assert not np.allclose(expected, mean_feature_counts([episode]))  # the expert's own choices differ


def test_the_maxent_policy_strategy_refuses_bad_weights_and_generators():
    with pytest.raises(ValueError, match="needs 7 finite weights"):
        MaxEntPolicyStrategy(np.ones(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match="needs 7 finite weights"):
        MaxEntPolicyStrategy([np.nan] * 7, np.random.default_rng(0))
    with pytest.raises(ValueError, match="samples with a numpy Generator"):
        MaxEntPolicyStrategy(np.ones(7), 0)
