"""``check_strategy(strategy)``: does a strategy keep the ``choose(state, rng) -> Decision`` contract?

In the spirit of scikit-learn's ``check_estimator`` and Gymnasium's ``check_env``:
it runs the strategy on small seeded synthetic states (``learning.synthetic``)
part-way through an episode, fresh, with one cost unit left, with the budget
spent, with an empty scene and with the feature query answered, and checks
each rule below. The first broken rule raises one :class:`StrategyCheckError`
naming the rule, the state and what the strategy did; a strategy that keeps
every rule gets a short :class:`StrategyCheckReport`.
"""

from __future__ import annotations

import copy
import hashlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from learning.actions import Decision, FeatureQuery, LabelQuery, NoQuery
from learning.errors import SettingsError
from learning.state import LearningState
from learning.synthetic import SyntheticTask, random_state
from learning.turn import admissible

RULES = (
    "returns a Decision with a one-sentence explanation",
    "asks only affordable, admissible actions",
    "leaves the state unchanged",
    "is deterministic given the rng",
    "stays quiet when the budget is spent",
    "asks no label query of an empty scene",
    "asks no second feature query",
)


class StrategyCheckError(SettingsError):
    """A strategy broke one rule of the ``choose(state, rng) -> Decision`` contract (the message says which)."""


@dataclass(frozen=True)
class StrategyCheckReport:
    """What ``check_strategy`` ran: the strategy's name, the rules it kept, the states and seeds it ran on."""

    name: str
    rules: tuple[str, ...]
    states: int
    seeds: tuple[int, ...]

    def __str__(self) -> str:
        return (f"{self.name}: passed {len(self.rules)} checks on {self.states} synthetic states (seeds "
                f"{', '.join(map(str, self.seeds))})")


def synthetic_states(seed: int, feature_selection: str | None = None) -> list[tuple[str, LearningState]]:
    """The seeded states a strategy is checked on, each with a few words saying what it is."""
    task = SyntheticTask(n_features=6, n_informative=2, seed=seed)

    def draw(n_train: int = 6, n_objects: int = 5, answered: bool = False) -> LearningState:
        return random_state(task, n_train, n_objects, np.random.default_rng(seed), feature_query_answered=answered,
                            budget=20.0, turns=30, feature_selection=feature_selection)

    fresh = LearningState(task.concepts, task.feature_names, 20.0, 30, feature_selection=feature_selection)
    fresh.observe_scene(0, task.sample(5, np.random.default_rng(seed))[0])
    one_left, spent, empty = draw(), draw(), draw(n_objects=0)
    one_left.place_progress(spent=19.0)
    spent.place_progress(spent=20.0)
    return [("a state part-way through an episode", draw()), ("a fresh state (no examples yet)", fresh),
            ("a state with one cost unit left", one_left), ("a state whose budget is spent", spent),
            ("a state with an empty scene (no objects)", empty),
            ("a state whose feature query was answered", draw(answered=True))]


def fingerprint(state: LearningState) -> str:
    """A digest of everything a strategy must not change: training set, subsets, budget and clock, scene, models."""
    digest = hashlib.sha256()

    def add(*values) -> None:
        for value in values:
            digest.update(value.tobytes() if isinstance(value, np.ndarray) else repr(value).encode())

    for example in state.examples:
        add(np.ascontiguousarray(example.x), example.concept, example.source, example.scene_id)
    add(sorted((c, None if s is None else tuple(np.asarray(s).tolist())) for c, s in state.feature_subsets.items()))
    add(state.progress, state.version, state.training_version, state.feature_selection, state.seconds_clock)
    scene = state.scene
    add(scene.scene_id, np.ascontiguousarray(scene.X), sorted(scene.asked), sorted(scene.demonstrated),
        sorted(scene.absent))
    if len(state.scene_X):
        add(np.ascontiguousarray(state.probabilities(np.array(state.scene_X))))  # refit models, not the cache
    return digest.hexdigest()


def check_strategy(strategy, seeds: Iterable[int] = (0, 1, 2)) -> StrategyCheckReport:
    """Run ``strategy`` on seeded synthetic states and check its contract; raises StrategyCheckError on the first
    broken rule (one readable message), else returns what passed."""
    name = str(getattr(strategy, "name", "") or type(strategy).__name__)
    if not callable(getattr(strategy, "choose", None)):
        raise StrategyCheckError(f"{name}: has no choose(state, rng) method (a strategy is a learning.Strategy, or "
                                 f"any object with choose(state, rng) -> Decision)")
    seeds = tuple(int(s) for s in seeds)
    states = 0
    for seed in seeds:
        for what, state in synthetic_states(seed, getattr(strategy, "feature_selection", None)):
            _check_one(strategy, name, state, f"{what}, seed {seed}", seed)
            states += 1
    return StrategyCheckReport(name, RULES, states, seeds)


def _check_one(strategy, name: str, state: LearningState, where: str, seed: int) -> None:
    def fail(rule: str, what: str) -> StrategyCheckError:
        return StrategyCheckError(f"{name} {rule}: on {where} it {what}")

    before = fingerprint(state)
    first = _choose(_twin(strategy), state, seed, lambda what: fail(RULES[0], what))
    if fingerprint(state) != before:
        raise fail(RULES[2], "changed the state (its training set, budget, clock, scene or models); choose may only "
                             "read the state, which the teaching loop changes")
    second = _choose(_twin(strategy), state, seed, lambda what: fail(RULES[0], what))
    if second != first:
        raise fail(RULES[3], f"chose {first.action!r} ('{first.explanation}') and then, with an rng of the same "
                             f"seed, {second.action!r} ('{second.explanation}'); draw random numbers only from rng")
    action = first.action
    if state.remaining_budget < min(state.costs[k] for k in ("label", "demo", "feature")) - 1e-9 \
            and action != NoQuery():
        raise fail(RULES[4], f"asked {action!r} with {state.remaining_budget:g} of {state.budget:g} left; return "
                             f"a NoQuery (Strategy.out_of_budget says why)")
    if len(state.scene_X) == 0 and isinstance(action, LabelQuery):
        raise fail(RULES[5], f"asked {action!r} of a scene with no objects; ask something else or stay quiet")
    if state.feature_query_asked and isinstance(action, FeatureQuery):
        raise fail(RULES[6], "asked the feature query again; it may be asked once (state.feature_query_asked)")
    allowed, reason = admissible(state, action)
    if allowed != action:
        raise fail(RULES[1], f"asked {action!r}, which the state refuses ({reason.removeprefix('Nothing to ask: ')})")


def refuse_invalid_decision(name: str, action, reason: str, turn: int) -> StrategyCheckError:
    """The error for a plug-in strategy that asked, on ``turn``, an ``action`` the state refuses (``reason``)."""
    return StrategyCheckError(f"strategy '{name}' asked {action!r} on turn {turn}, which the state refuses "
                              f"({reason.removeprefix('Nothing to ask: ').rstrip('.')}); a strategy asks only "
                              f"affordable, admissible actions, so the episode stops here (the turns before are "
                              f"recorded)")


def _twin(strategy):
    """A copy of ``strategy`` as it was before this check (a strategy may remember things within an episode)."""
    try:
        return copy.deepcopy(strategy)
    except Exception:  # a strategy that can't be copied is checked as it is
        return strategy


def _choose(strategy, state: LearningState, seed: int, fail: Callable[[str], StrategyCheckError]) -> Decision:
    try:
        decision = strategy.choose(state, np.random.default_rng(seed))
    except Exception as error:  # the strategy's own error: reported as the broken rule, in one line
        raise fail(f"raised {type(error).__name__}: {error}") from None
    if not isinstance(decision, Decision):
        raise fail(f"returned {decision!r}; return learning.Decision(action, explanation)")
    if not isinstance(decision.explanation, str) or not decision.explanation.strip():
        raise fail(f"gave the explanation {decision.explanation!r}; say in one sentence why it asks this")
    if getattr(decision.action, "kind", None) not in state.costs:
        raise fail(f"returned the action {decision.action!r}; return a LabelQuery, DemoQuery, FeatureQuery or "
                   f"NoQuery")
    return decision
