"""Accuracy on held-out instances (thesis eq. 6.4 for one training set)."""

from __future__ import annotations

import numpy as np


def accuracy(predicted, truth) -> float:
    """Fraction of instances whose predicted concept equals the true one."""
    predicted, truth = np.asarray(predicted, dtype=object), np.asarray(truth, dtype=object)
    if predicted.shape != truth.shape:
        raise ValueError(f"predictions {predicted.shape} and truth {truth.shape} differ in shape")
    if len(truth) == 0:
        raise ValueError("accuracy needs at least one test instance")
    return float(np.mean(predicted == truth))


def most_probable_accuracy(P, concepts, truth) -> float:
    """Accuracy of the most probable concept of every row of p(y|x) (``P``: rows x concepts, as
    ``LearningState.predict`` decides)."""
    return accuracy(np.array(concepts, dtype=object)[np.argmax(np.asarray(P), axis=-1)], truth)
