"""DT's Why in words (learning/decision/reasons.py): the feature that decided, named without utility numbers,
on hand-made states; the decision's terms sum to EU(a*) - EU(no query)."""

import re

import numpy as np
import pytest

from learning.actions import NoQuery
from learning.decision.reasons import PHRASES, why_ask, why_quiet
from learning.state import LearningState
from learning.strategies import DecisionTheoreticStrategy
from learning.synthetic import SyntheticTask

TASK = SyntheticTask(n_features=10, n_informative=3, seed=1)
DECIMAL = re.compile(r"\d[.,]\d")


def hand_made_state(per_concept: list[int], objects: int, seed: int = 0, budget: float = 40.0,
                    feature_query_asked: bool = True) -> LearningState:
    """``per_concept[i]`` examples of concept i (balanced when all equal), a scene of ``objects`` objects, the
    feature question already asked (as in the stalls of issue 39) unless ``feature_query_asked`` is False."""
    rng = np.random.default_rng(seed)
    state = LearningState(TASK.concepts, TASK.feature_names, budget, 120, change_every=5)
    X = np.vstack([TASK.sample(k, rng, np.eye(len(TASK.concepts))[i])[0] for i, k in enumerate(per_concept)])
    state.add_prior(X, [c for c, k in zip(TASK.concepts, per_concept) for _ in range(k)])
    state.observe_scene(0, TASK.sample(objects, rng)[0])
    state.place_progress(turn=20, spent=13.0, feature_query_asked=feature_query_asked)
    return state


def test_a_stalled_state_with_balanced_counts_says_its_examples_would_get_less_even():
    state = hand_made_state([3] * len(TASK.concepts), 55)
    decision = DecisionTheoreticStrategy({"classifier_discriminability": 1.0,
                                          "class_distribution_uniformity": 1.0}).choose(state, np.random.default_rng(0))
    terms = dict(decision.terms)
    assert decision.action == NoQuery()
    assert terms["class_distribution_uniformity"] < 0 < terms["classifier_discriminability"]
    assert decision.explanation == ("Nothing to ask: asking now would make my examples less even, which outweighs "
                                    "what I expect to learn.")
    assert not DECIMAL.search(decision.explanation)


def test_a_state_where_the_learning_gain_dominates_names_what_it_expects_to_learn():
    state = hand_made_state([1, 4, 4, 4][: len(TASK.concepts)], 8)
    strategy = DecisionTheoreticStrategy({"classifier_discriminability": 1.0,
                                          "class_distribution_uniformity": 0.05})
    decision = strategy.choose(state, np.random.default_rng(0))
    terms = dict(decision.terms)
    assert decision.action != NoQuery()
    assert max(terms, key=terms.get) == "classifier_discriminability"
    assert "I expect to learn the most about" in decision.explanation
    assert not DECIMAL.search(decision.explanation)
    candidates = strategy.last_candidates
    utilities = candidates.utilities(strategy.weights)
    chosen = candidates.actions.index(decision.action)
    assert sum(terms.values()) == pytest.approx(utilities[chosen] - utilities[-1], abs=1e-12)


@pytest.mark.parametrize("weights", ["dt-iros", "dt-task", "dt-task-env", "dt-task-env-thesis"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_dt_sentence_holds_a_number_with_decimals(weights, seed):
    strategy = DecisionTheoreticStrategy(weights)
    for per_concept, objects in (([3] * len(TASK.concepts), 30), ([0, 2, 5, 1][: len(TASK.concepts)], 6)):
        for asked in (True, False):
            state = hand_made_state(per_concept, objects, seed, feature_query_asked=asked)
            decision = strategy.choose(state, np.random.default_rng(seed))
            assert decision.explanation.endswith(".") and not DECIMAL.search(decision.explanation), \
                decision.explanation


def test_every_feature_has_words_for_each_side_and_the_sentences_follow_the_largest_term():
    from learning.decision.habits import EXTENDED_FEATURE_NAMES
    assert set(PHRASES) == set(EXTENDED_FEATURE_NAMES)
    terms = (("classifier_discriminability", 0.004), ("class_distribution_uniformity", -0.0125),
             ("non_query_time", 0.001))
    assert why_quiet(terms) == "asking now would make my examples less even, which outweighs what I expect to learn"
    assert why_ask(terms, "fruit", "label") == "I expect to learn the most about fruit from this label"
    assert why_ask((("class_distribution_uniformity", 0.01),), "fruit", "label") == \
        "it makes my examples more even across the concepts"
    assert why_quiet(()) == "no question would teach me anything now"
