"""dt-voi (issue 40): its contract, when it asks and when it stays quiet, its price rule, its reason sentence."""

import numpy as np
import pytest

from learning import LabelQuery, NoQuery, check_strategy, make_strategy
from learning.decision.voi import answer_value, price_rule, voi_gains
from learning.state import LearningState
from learning.strategies.voi import VoiSettings
from learning.synthetic import SyntheticTask, run_episode

CONCEPTS = ("apple", "cup")
FEATURES = ("x", "y")


LABELS_ONLY = {"label": 1, "demo": 21, "feature": 21, "none": 0}


def state_with(prior_X, prior_labels, scene, budget=20.0, turns=30, costs=None) -> LearningState:
    state = LearningState(CONCEPTS, FEATURES, budget, turns, costs=costs)
    state.add_prior(np.array(prior_X, dtype=float), prior_labels)
    state.observe_scene(0, np.array(scene, dtype=float))
    return state


def test_dt_voi_keeps_the_strategy_contract():
    report = check_strategy(make_strategy("dt-voi"), seeds=(0, 1))
    assert report.states == 12 and report.name == "dt-voi"


def test_one_label_that_fixes_many_predictions_is_asked():
    # apples near (-3, 0), cups near (3, 0); the scene: one object by the apples and a tight cluster of eight
    # objects midway up at (0, 3), which no model can place yet: one label there places all eight
    rng = np.random.default_rng(5)
    prior = np.vstack([rng.normal((-3, 0), 0.3, (4, 2)), rng.normal((3, 0), 0.3, (4, 2))])
    cluster = rng.normal((0, 3), 0.05, (8, 2))
    scene = np.vstack([[(-3, 0)], cluster])
    # with every kind priced it asks too (a demonstration: DT's p(x|y) treats the cluster's objects as
    # independent, so one of them is likely the one shown; docs/strategies.md, limits)
    every_kind = state_with(prior, ["apple"] * 4 + ["cup"] * 4, scene)
    assert make_strategy("dt-voi").choose(every_kind, np.random.default_rng(0)).action != NoQuery()
    state = state_with(prior, ["apple"] * 4 + ["cup"] * 4, scene, costs=LABELS_ONLY)
    strategy = make_strategy("dt-voi", pool="scene")
    decision = strategy.choose(state, np.random.default_rng(0))
    assert isinstance(decision.action, LabelQuery) and decision.action.object_index >= 1
    gains = strategy.last_gains
    chosen = gains.actions.index(decision.action)
    lone = gains.actions.index(LabelQuery(0))
    assert gains.objects_right[chosen] > 1.0 > gains.objects_right[lone] * 10
    assert decision.explanation.startswith(f"I ask what object {decision.action.object_index + 1} is: I expect to "
                                           f"get about ")
    assert "more of the 9 objects I have seen right" in decision.explanation


def test_nothing_uncertain_stays_quiet_even_when_asking_is_free():
    # many examples of two far-apart concepts; the scene holds objects right on top of them: no answer can
    # change a prediction, so every question is worth nothing, and the budget outlasts the turns (price 0)
    rng = np.random.default_rng(6)
    prior = np.vstack([rng.normal((-4, 0), 0.2, (15, 2)), rng.normal((4, 0), 0.2, (15, 2))])
    scene = np.vstack([rng.normal((-4, 0), 0.1, (3, 2)), rng.normal((4, 0), 0.1, (3, 2))])
    state = state_with(prior, ["apple"] * 15 + ["cup"] * 15, scene, budget=100.0, turns=10)
    strategy = make_strategy("dt-voi")
    decision = strategy.choose(state, np.random.default_rng(0))
    assert decision.action == NoQuery()
    assert strategy.last_gains.price.per_unit == 0.0
    assert float(np.max(strategy.last_gains.objects_right)) < 0.05
    assert decision.explanation.startswith("Nothing to ask: I am sure enough of what I see")


@pytest.mark.parametrize("budget, cheapest, turns, best, n, per_unit", [
    (20.0, 1.0, 30, 0.6, 20, (1 - 20 / 30) * 0.6),  # bench_peers' allocation at its first turn
    (30.0, 1.0, 30, 0.6, 30, 0.0),  # the budget covers every turn: asking displaces nothing
    (500.0, 1.0, 150, 2.0, 500, 0.0),
    (5.0, 2.0, 10, 1.0, 2, 0.8),  # two questions of cost 2 in ten turns
    (0.5, 1.0, 4, 1.0, 0, 1.0),  # nothing affordable: a unit is worth the best question later
])
def test_the_price_rule_at_a_few_allocations(budget, cheapest, turns, best, n, per_unit):
    price = price_rule(budget, cheapest, turns, best)
    assert price.questions_left == n and price.turns_left == turns
    assert price.per_unit == pytest.approx(per_unit)
    assert price.of(2.0) == pytest.approx(2 * per_unit)


def test_answer_values_are_zero_without_a_changed_prediction_and_count_objects_that_flip():
    now = np.array([[0.9, 0.1], [0.6, 0.4]])
    same = np.array([[0.95, 0.05], [0.55, 0.45]])
    flipped = np.array([[0.9, 0.1], [0.2, 0.8]])
    assert answer_value(now, same, "error") == pytest.approx(0.0)
    assert answer_value(now, flipped, "error") == pytest.approx(0.8 - 0.2)
    assert answer_value(now, now, "log") == pytest.approx(0.0) and answer_value(now, flipped, "log") > 0


def test_the_gains_of_the_pool_decide_the_price():
    task = SyntheticTask(n_features=6, n_informative=2, seed=100)
    rng = np.random.default_rng(100)
    state = LearningState(task.concepts, task.feature_names, 10.0, 30)
    X, labels = task.sample(6, rng)
    state.add_prior(X, labels)
    state.observe_scene(0, task.sample(5, rng)[0])
    pool = task.sample(20, rng)[0]
    gains = voi_gains(state, pool)
    labels_only = [i for i, a in enumerate(gains.actions) if a.kind == "label"]
    assert gains.judged == 25 and len(labels_only) == 5
    # g* is the best label gain over the 25 rows, at least the scene's best; 10 questions for 30 turns
    assert gains.price.best_later >= gains.gain[labels_only].max() - 1e-12
    assert gains.price.per_unit == pytest.approx((1 - 10 / 30) * gains.price.best_later)


def test_same_seed_same_choices_and_reasons():
    task = SyntheticTask(n_features=8, n_informative=3, seed=101)

    def play():
        episode = run_episode(make_strategy("dt-voi"), task, np.random.default_rng(101), budget=8, turns=12,
                              change_every=4, objects=6, test_objects=20)
        return episode.actions, episode.explanations

    first, second = play(), play()
    assert first == second
    assert any(a.kind != "none" for a in first[0])


def test_the_settings_file_is_read_and_a_bad_option_is_refused(tmp_path):
    assert VoiSettings.load() == VoiSettings(loss="error", pool="seen", pool_limit=200)
    bad = tmp_path / "voi.toml"
    bad.write_text('[voi]\nloss = "hinge"\npool = "seen"\npool_limit = 10\n')
    with pytest.raises(Exception, match="hinge"):
        VoiSettings.load(bad)
    with pytest.raises(ValueError, match="pool in"):
        make_strategy("dt-voi", pool="everything")
