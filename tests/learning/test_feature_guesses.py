"""Guesses of the feature answer (issue 49 item 3): each is a distribution over subsets drawn from the learner's
own training set, and the exact refit they are judged with is the learner's own fit."""

import numpy as np
import pytest

from learning.synthetic import SyntheticTask, random_state
from learning.whatif.base import feature_query_subsets
from learning.whatif.fast import feature_outcomes
from learning.whatif.feature_guesses import GUESSES, generated, guessed_answers, refit_probabilities

TASK = SyntheticTask(n_features=6, n_informative=2, seed=3)


def state_with(n_train, seed=0):
    return random_state(TASK, n_train, 5, np.random.default_rng(seed))


@pytest.mark.parametrize("guess", GUESSES)
@pytest.mark.parametrize("n_train", [3, 12, 30])
def test_every_guess_is_a_distribution_over_subsets_of_the_features(guess, n_train):
    state = state_with(n_train)
    answers = guessed_answers(state, guess)
    if answers:
        assert sum(p for p, _ in answers) == pytest.approx(1.0)
    for _, subsets in answers:
        assert set(subsets) == set(state.concepts)
        for subset in subsets.values():
            assert subset is None or (len(subset) and set(np.asarray(subset).tolist()) <= set(range(6)))


def test_no_example_no_answer_and_unknown_guesses_are_refused():
    state = state_with(0)
    assert all(guessed_answers(state, guess) == [] for guess in GUESSES)
    with pytest.raises(ValueError, match="accepted: per-concept"):
        guessed_answers(state, "oracle")


def test_the_union_holds_every_generated_subset_and_only_those():
    state = state_with(30, seed=4)
    subsets, made = feature_query_subsets(state), generated(state)
    assert any(made.values())
    [(p, union)] = guessed_answers(state, "union")
    expected = np.unique(np.concatenate([subsets[c] for c in state.concepts if made[c]]))
    for c in state.concepts:
        np.testing.assert_array_equal(union[c], expected)
    assert len(guessed_answers(state, "generated-only")) == sum(made.values())


def test_the_exact_refit_is_the_learners_fit_and_the_engines_feature_outcome():
    state = state_with(12, seed=2)
    own = refit_probabilities(state, dict(state.fitted_feature_subsets), state.scene_X)
    np.testing.assert_allclose(own, state.probabilities(), atol=1e-8)
    per_concept = guessed_answers(state, "per-concept")
    fast = feature_outcomes(state)
    for y, (_, subsets) in enumerate(per_concept):  # today's guess is what the fast engine simulates
        np.testing.assert_allclose(refit_probabilities(state, subsets, state.scene_X), fast[y], atol=1e-4)
