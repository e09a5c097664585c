"""The expert-habit decision features (learning/decision/habits.py, issue 27): each in [0, 1], each showing its
habit on a hand-made state."""

import numpy as np

from learning.decision.habits import (
    concepts_without_example,
    feature_query_overdue,
    pace_overrun,
    unsure_objects,
    unsure_unlabelled,
)
from learning.irl.imitation import ablation_weights, three_way_split


def test_pace_overrun_is_zero_within_the_expert_pace_and_grows_past_it():
    # budget 15, 30 turns: by the end of turn 3 the expert may have spent 15 (3 + 3) / 30 = 3
    assert pace_overrun(3, 15, 3, 30) == 0.0
    assert np.isclose(pace_overrun(4, 15, 3, 30), 4 / 15 - 0.2)
    assert pace_overrun(15, 15, 0, 30) <= 1.0 and pace_overrun(0, 0, 3, 30) == 0.0


def test_feature_query_overdue_grows_until_asked():
    assert feature_query_overdue(False, 1) < feature_query_overdue(False, 4) < feature_query_overdue(False, 9) == 1.0
    assert feature_query_overdue(True, 4) == 0.0


def test_concepts_without_example_counts_the_unseen_concepts():
    assert concepts_without_example(np.array([0, 0, 2, 1])) == 0.5
    assert concepts_without_example(np.array([1, 1, 1, 1])) == 0.0
    np.testing.assert_allclose(concepts_without_example(np.array([[0, 1], [0, 0]])), [0.5, 1.0])


def test_unsure_unlabelled_counts_unsure_objects_not_yet_labelled():
    P = np.array([[0.9, 0.1], [0.5, 0.5], [0.45, 0.55], [0.1, 0.9]])
    unsure = unsure_objects(P)
    np.testing.assert_array_equal(unsure, [False, True, True, False])
    assert unsure_unlabelled(unsure, np.zeros(4, dtype=bool)) == 0.5
    assert unsure_unlabelled(unsure, np.array([False, True, False, False])) == 0.25  # labelling an unsure one
    assert unsure_unlabelled(unsure, np.array([True, False, False, False])) == 0.5  # a sure one changes nothing


def test_three_way_split_and_the_ablation_rule():
    parts = three_way_split(list(range(30)), np.random.default_rng(0))
    assert [len(p) for p in parts] == [10, 10, 10] and sorted(sum(parts, [])) == list(range(30))
    learned = {"classifier_discriminability": 2.0, "class_distribution_uniformity": 0.0, "instance_variation": 0.0,
               "prediction_margin": 0.0, "budget_consumption": -1.0, "remaining_time": 0.0, "non_query_time": -1.0,
               "pace_overrun": -5.0, "feature_query_overdue": -1.0, "concepts_without_example": -2.0,
               "unsure_unlabelled": -3.0}
    ablations = ablation_weights(learned, {"classifier_discriminability": 1.0})
    assert ablations["dt-task-env-no-env"]["pace_overrun"] == 0.0
    assert ablations["dt-task-env-no-env"]["unsure_unlabelled"] == -3.0
    habits = ablations["dt-task-habits"]
    assert habits["classifier_discriminability"] == 2.0 and habits["budget_consumption"] == 0.0
    assert habits["pace_overrun"] == -5.0


def test_selection_by_likelihood_recovers_a_known_expert_on_the_synthetic_task():
    """The imitation protocol (split seeds x fit seeds x both policy forms, each fit's iterate kept by validation
    log-likelihood, the median fit shipped) on a greedy expert with known weights on the synthetic ch7 task:
    the shipped fit and every other agree with the held-out expert on >= 0.9 of turns (issue 27)."""
    from learning.irl.imitation import baseline_scores, fit_protocol, shipped_fit
    from tests.learning.test_irl import TRUE_WEIGHTS, demonstrations, greedy_policy

    episodes = demonstrations(greedy_policy(TRUE_WEIGHTS), np.random.default_rng(7), 30)
    fits = fit_protocol(episodes, split_seeds=[0, 1], fit_seeds=[0, 1])
    assert len(fits) == 8 and all(fit.weights.provenance["select_by"] == "log_likelihood" for fit in fits)
    kept = shipped_fit(fits)
    assert kept.held_out_scores["exact_agreement"] >= 0.9 and kept.held_out_scores["turns"] > 100  # 10 episodes
    assert min(fit.held_out_scores["exact_agreement"] for fit in fits) >= 0.9
    quiet = baseline_scores(episodes)["always_quiet"]["exact_agreement"]
    assert kept.held_out_scores["exact_agreement"] > quiet + 0.1  # far above always-quiet
