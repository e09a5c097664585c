"""Kendall's W with the tie correction (learning.significance.kendalls_w), against values worked by hand."""

import numpy as np
import pytest

from learning.significance import kendalls_w, ranks_high_first


def test_ranks_put_the_highest_score_first_and_share_ties():
    assert ranks_high_first([0.2, 0.9, 0.5, 0.5]).tolist() == [4.0, 1.0, 2.5, 2.5]


def test_perfect_agreement_is_one_and_opposite_rankings_zero():
    rng = np.random.default_rng(0)
    same = kendalls_w([[1, 2, 3, 4]] * 3, rng, resamples=50)
    assert same["w"] == pytest.approx(1.0) and same["ci"] == [1.0, 1.0]
    assert same["chi2"] == pytest.approx(9.0) and same["df"] == 3  # m (n - 1) W = 3 x 3
    assert kendalls_w([[1, 2, 3], [3, 2, 1]], rng, resamples=50)["w"] == pytest.approx(0.0)


def test_the_tie_correction_matches_a_hand_computation():
    # raters: (1, 2, 3), (1.5, 1.5, 3): totals 2.5, 3.5, 6 -> S = (2.5-4)^2 + (3.5-4)^2 + 2^2 = 6.5;
    # T = 2^3 - 2 = 6 for the second rater; W = 12 x 6.5 / (4 x 24 - 2 x 6) = 78 / 84
    result = kendalls_w([[1, 2, 3], [1.5, 1.5, 3]], np.random.default_rng(0), resamples=10)
    assert result["w"] == pytest.approx(78 / 84)


def test_too_few_raters_or_items_is_refused():
    with pytest.raises(ValueError, match="at least 2 raters and 2 items"):
        kendalls_w([[1, 2, 3]], np.random.default_rng(0))
