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
