"""Questioning strategies: each looks at the learning state and returns one Decision.

``make_strategy(name)`` builds one by name; ``STRATEGY_NAMES`` lists them all.

========== ==================================================================
passive    P: demonstrations only, the least represented concept first (every feature)
active     A: label queries by uncertainty (entropy, eq. 6.1) (every feature)
passive-fs P with computational feature selection (ES), as the thesis's baseline
active-fs  A (U-sampling) with computational feature selection (ES), as the thesis's baseline
random     R: any affordable query at random
hfs-passive HFS+P: the feature query first, then P
hfs-active HFS+A: the feature query first, then A
all-cd     All/CD: feature query, a few demos keeping classes uniform, then A
dt         DT with the weights in learning/decision/presets/dt.toml (or ``weights=``)
dt-iros    DT on ACD and CDU (thesis ch. 6)
dt-task    DT on ACD, CDU, IV and PM (thesis ch. 7)
dt-task-env DT on all seven decision features (thesis ch. 7; IRL weights)
scripted-expert the scripted expert of thesis §7.4.1 (rules in data/scripted-expert.toml)
rl:FILE    a trained questioner policy (teachbot train-questioner; beyond the thesis)
========== ==================================================================
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from learning.errors import SettingsError, did_you_mean
from learning.strategies.active import ActiveFeatureSelectingStrategy, ActiveStrategy
from learning.strategies.all_cd import AllClassDistributionStrategy
from learning.strategies.base import Strategy
from learning.strategies.decision_theoretic import DecisionTheoreticStrategy
from learning.strategies.hfs import HfsActiveStrategy, HfsPassiveStrategy
from learning.strategies.passive import PassiveFeatureSelectingStrategy, PassiveStrategy
from learning.strategies.random_choice import RandomStrategy
from learning.strategies.rl_questioner import PREFIX as RL_PREFIX
from learning.strategies.rl_questioner import RLQuestionerStrategy
from learning.strategies.scripted_expert import ScriptedExpertStrategy

STRATEGIES: dict[str, Callable[..., Strategy]] = {
    "passive": PassiveStrategy,
    "active": ActiveStrategy,
    "random": RandomStrategy,
    "hfs-passive": HfsPassiveStrategy,
    "hfs-active": HfsActiveStrategy,
    "all-cd": AllClassDistributionStrategy,
    "dt": partial(DecisionTheoreticStrategy, "dt"),
    "dt-iros": partial(DecisionTheoreticStrategy, "dt-iros"),
    "dt-task": partial(DecisionTheoreticStrategy, "dt-task"),
    "dt-task-env": partial(DecisionTheoreticStrategy, "dt-task-env"),
    "scripted-expert": ScriptedExpertStrategy,
    "passive-fs": PassiveFeatureSelectingStrategy,
    "active-fs": ActiveFeatureSelectingStrategy,
}
STRATEGY_NAMES = tuple(STRATEGIES)


def make_strategy(name: str, **options) -> Strategy:
    """The strategy called ``name``; a clear error lists the accepted names.

    Options go to the strategy's constructor, e.g. ``make_strategy("dt", weights={...}, engine="reference")``
    or ``make_strategy("all-cd", examples_per_concept=3)``.
    """
    if str(name).startswith(RL_PREFIX):  # a policy file: its path keeps its case
        return RLQuestionerStrategy(str(name)[len(RL_PREFIX):], name=str(name), **options)
    key = str(name).strip().lower()
    if key not in STRATEGIES:
        raise SettingsError(f"unknown strategy '{name}'{did_you_mean(key, STRATEGY_NAMES)}; choose one of: "
                            f"{', '.join(STRATEGY_NAMES)}, or {RL_PREFIX}FILE (a trained questioner policy .toml)")
    if key == "dt" and "weights" in options:
        return DecisionTheoreticStrategy(name="dt", **options)
    try:
        return STRATEGIES[key](**options)
    except TypeError as error:
        raise SettingsError(f"strategy '{key}' does not take the options {sorted(options)} ({error})") from None


__all__ = ["STRATEGIES", "STRATEGY_NAMES", "DecisionTheoreticStrategy", "Strategy", "make_strategy"]
