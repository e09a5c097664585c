"""Mann-Whitney comparisons and learning-curve summaries."""

import numpy as np
import pytest

from learning.significance import accuracy_after_questions, mann_whitney, mean_and_standard_error


def test_clearly_better_sample_is_significant_one_tailed():
    better, worse = [0.9, 0.92, 0.95, 0.91, 0.93], [0.6, 0.62, 0.58, 0.65, 0.61]
    result = mann_whitney("dt", better, "passive", worse, "greater")
    assert result.p < 0.01 and result.significant and result.mean_a > result.mean_b
    assert mann_whitney("dt", better, "passive", worse, "less").p > 0.9


def test_identical_samples_are_not_significant():
    result = mann_whitney("a", [0.5] * 5, "b", [0.5] * 5)
    assert result.p == 1.0 and not result.significant


def test_bad_alternative_is_named():
    with pytest.raises(ValueError, match="two-sided, greater, less"):
        mann_whitney("a", [1], "b", [2], "bigger")


def test_mean_and_standard_error_by_column():
    curves = np.array([[0.0, 1.0, np.nan, 5.0], [2.0, 3.0, np.nan, np.nan], [4.0, np.nan, np.nan, np.nan]])
    mean, error = mean_and_standard_error(curves)
    assert mean[:2] == pytest.approx([2.0, 2.0]) and np.isnan(mean[2]) and mean[3] == 5.0
    assert error[0] == pytest.approx(2.0 / np.sqrt(3)) and error[1] == pytest.approx(np.sqrt(2) / np.sqrt(2))
    assert np.isnan(error[2]) and error[3] == 0.0


def test_accuracy_after_questions_takes_the_first_turn_reaching_the_count():
    questions = np.array([0, 1, 1, 2, 4])
    accuracy = np.array([0.2, 0.3, 0.35, 0.5, 0.7])
    assert accuracy_after_questions(questions, accuracy, [0, 1, 2, 3, 4, 5]) == pytest.approx(
        [0.2, 0.3, 0.5, 0.7, 0.7, np.nan], nan_ok=True)


# -- paired tests, clustered intervals and Holm's correction (issue 26) ---------------------------------------
from learning.significance import cluster_bootstrap_ci, holm, rank_biserial, wilcoxon_paired  # noqa: E402


def test_a_paired_test_sees_a_small_consistent_gain_that_mann_whitney_misses():
    rng = np.random.default_rng(3)
    episode_difficulty = rng.normal(0.7, 0.1, size=12)  # shared by both strategies: the pairing removes it
    a, b = episode_difficulty + 0.02, episode_difficulty
    assert mann_whitney("a", a, "b", b, "greater").p > 0.2
    paired = wilcoxon_paired("a", a, "b", b, "greater")
    assert paired.p < 0.001 and paired.effect == 1.0 and paired.n == 12
    assert paired.median_difference == pytest.approx(0.02) and paired.ci[0] == pytest.approx(0.02)


def test_paired_refuses_unequal_samples_and_calls_no_difference_no_evidence():
    with pytest.raises(ValueError, match="same number of values"):
        wilcoxon_paired("a", [1, 2], "b", [1])
    same = wilcoxon_paired("a", [0.5, 0.6], "b", [0.5, 0.6])
    assert same.p == 1.0 and not same.significant and same.effect == 0.0


def test_rank_biserial_is_plus_one_when_every_pair_favours_a():
    assert rank_biserial([0.1, 0.2, 0.3]) == 1.0 and rank_biserial([-0.1, -0.2]) == -1.0
    assert rank_biserial([0.0, 0.0]) == 0.0 and -1 < rank_biserial([0.3, -0.1, 0.2]) < 1


def test_the_cluster_bootstrap_is_wider_when_pools_differ_and_is_deterministic():
    rng = np.random.default_rng
    pools = np.repeat(np.arange(5), 5)
    shared = np.repeat([0.2, -0.1, 0.15, 0.05, -0.05], 5)  # one offset per pool: episodes of a pool agree
    d = shared + np.random.default_rng(0).normal(0, 0.01, size=25)
    clustered = cluster_bootstrap_ci(d, pools, rng(1))
    naive = cluster_bootstrap_ci(d, range(25), rng(1))
    assert clustered[1] - clustered[0] > 1.5 * (naive[1] - naive[0])
    assert cluster_bootstrap_ci(d, pools, rng(1)) == clustered
    assert cluster_bootstrap_ci(d, [(0, p) for p in pools], rng(1)) == clustered  # any hashable label
    with pytest.raises(ValueError, match="one cluster per difference"):
        cluster_bootstrap_ci(d, pools[:3], rng(1))


def test_holm_adjusts_step_down_and_keeps_the_order():
    comparisons = [mann_whitney("a", [1.0, 2.0], "b", [0.0, 1.0])] * 3
    ps = [0.01, 0.04, 0.03]
    from dataclasses import replace
    adjusted = holm([replace(c, p=p) for c, p in zip(comparisons, ps)])
    assert [c.p_holm for c in adjusted] == pytest.approx([0.03, 0.06, 0.06])
    assert adjusted[0].significant and not adjusted[1].significant and not adjusted[2].significant
    assert holm([]) == []


def test_one_cluster_gives_no_interval_and_one_difference_a_cluster_is_the_plain_bootstrap():
    d = np.array([0.1, 0.3, 0.2, 0.4])
    assert cluster_bootstrap_ci(d, [7, 7, 7, 7], np.random.default_rng(1)) is None
    assert wilcoxon_paired("a", d, "b", np.zeros(4), clusters=[7] * 4).ci is None
    plain = wilcoxon_paired("a", d, "b", np.zeros(4), rng=np.random.default_rng(1))
    assert plain.clusters == 4 and plain.ci == cluster_bootstrap_ci(d, range(4), np.random.default_rng(1))
