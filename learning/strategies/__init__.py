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
dt-iros-v1 dt-iros's hand-set weights from before the calibration rule (docs/calibration.md)
dt-task-v1 dt-task's hand-set weights from before the calibration rule (docs/calibration.md)
dt-task-env DT-task-env on the thesis's seven features, per-turn IRL with the thesis's signs (thesis ch. 7; issue 39)
dt-task-env-v1 DT on the seven decision features and the expert-habit ones (issue 27's IRL fit)
dt-task-env-thesis DT-task-env on the thesis's seven features only (the earlier trajectory-level IRL fit)
dt-task-env-no-env ablation: dt-task-env's weights without the environment features (docs/irl.md)
dt-task-habits ablation: DT-task's learning weights with dt-task-env's habit-feature weights (docs/irl.md)
scripted-expert the scripted expert of thesis §7.4.1 (rules in data/scripted-expert.toml)
dt-voi     the question whose expected gain in objects right beats its price, from the allocation (beyond the thesis)
rl:FILE    a trained questioner policy (teachbot train-questioner; beyond the thesis)
pkg.mod:Cls your own strategy class, imported from an importable module (runs your code; plugins.py)
========== ==================================================================

``check_strategy_name(name)`` is the one check of a name that callers (suites, study files, the
command line, a resumed session) use before anything runs.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from pathlib import Path

from learning.errors import SettingsError, did_you_mean
from learning.strategies.active import ActiveFeatureSelectingStrategy, ActiveStrategy
from learning.strategies.all_cd import AllClassDistributionStrategy
from learning.strategies.base import Strategy
from learning.strategies.decision_theoretic import DecisionTheoreticStrategy
from learning.strategies.hfs import HfsActiveStrategy, HfsPassiveStrategy
from learning.strategies.passive import PassiveFeatureSelectingStrategy, PassiveStrategy
from learning.strategies.plugins import FORM as PLUGIN_FORM
from learning.strategies.plugins import is_plugin_spec, load_plugin, plugin_file_label
from learning.strategies.random_choice import RandomStrategy
from learning.strategies.rl_questioner import PREFIX as RL_PREFIX
from learning.strategies.rl_questioner import RLQuestionerStrategy
from learning.strategies.scripted_expert import ScriptedExpertStrategy
from learning.strategies.voi import ValueOfInformationStrategy

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
    "dt-iros-v1": partial(DecisionTheoreticStrategy, "dt-iros-v1"),
    "dt-task-v1": partial(DecisionTheoreticStrategy, "dt-task-v1"),
    "dt-task-env": partial(DecisionTheoreticStrategy, "dt-task-env"),
    "dt-task-env-v1": partial(DecisionTheoreticStrategy, "dt-task-env-v1"),
    "dt-task-env-thesis": partial(DecisionTheoreticStrategy, "dt-task-env-thesis"),
    "dt-task-env-no-env": partial(DecisionTheoreticStrategy, "dt-task-env-no-env"),
    "dt-task-habits": partial(DecisionTheoreticStrategy, "dt-task-habits"),
    "scripted-expert": ScriptedExpertStrategy,
    "passive-fs": PassiveFeatureSelectingStrategy,
    "active-fs": ActiveFeatureSelectingStrategy,
    "dt-voi": ValueOfInformationStrategy,
}
STRATEGY_NAMES = tuple(STRATEGIES)
# the strategy of the library's TeachingLoop, of EpisodeSettings, and of teach and demo, written once
DEFAULT_STRATEGY = "dt-task"
# NAME+turns: the DT strategy NAME with time in turns (remaining time in turns, no gain per second) even in an
# episode with embodied costs, to compare with NAME (thesis §8.2.2; docs/strategies.md)
TURNS_SUFFIX = "+turns"


ACCEPTED = (f"{', '.join(STRATEGY_NAMES)}, {RL_PREFIX}FILE (a trained questioner policy .toml), or "
            f"{PLUGIN_FORM}")


def make_strategy(name: str, **options) -> Strategy:
    """The strategy called ``name``, every form of a name decoded here; a clear error lists the accepted names.

    ``name`` is a registered name, ``NAME+turns`` (the DT strategy NAME reasoning in turns even in an episode
    with embodied costs), ``rl:FILE`` or ``module.path:ClassName`` (imports and runs the user's code).
    Options go to the strategy's constructor, e.g. ``make_strategy("dt", weights={...}, engine="reference")``
    or ``make_strategy("all-cd", examples_per_concept=3)``.
    """
    if str(name).endswith(TURNS_SUFFIX):
        strategy = make_strategy(str(name)[: -len(TURNS_SUFFIX)], **options)
        if not isinstance(strategy, DecisionTheoreticStrategy):
            raise SettingsError(f"'{name}': only a DT strategy has a {TURNS_SUFFIX} variant (it ignores embodied "
                                "costs)")
        strategy.embodied, strategy.name = False, str(name)
        return strategy
    if str(name).startswith(RL_PREFIX):  # a policy file: its path keeps its case
        return RLQuestionerStrategy(str(name)[len(RL_PREFIX):], name=str(name), **options)
    if is_plugin_spec(name):  # module.path:ClassName keeps its case too
        return load_plugin(str(name), **options)
    key = str(name).strip().lower()
    if key not in STRATEGIES:
        raise SettingsError(f"unknown strategy '{name}'{did_you_mean(key, STRATEGY_NAMES)}; choose one of: "
                            f"{ACCEPTED}")
    if key == "dt" and "weights" in options:
        return DecisionTheoreticStrategy(name="dt", **options)
    try:
        return STRATEGIES[key](**options)
    except TypeError as error:
        raise SettingsError(f"strategy '{key}' does not take the options {sorted(options)} ({error})") from None


def is_external(name) -> bool:
    """True for a strategy outside the registry: ``rl:FILE`` or ``module.path:ClassName`` (the user's own; no
    stored baseline holds it)."""
    return str(name).startswith(RL_PREFIX) or is_plugin_spec(name)


def check_strategy_name(name: str, known=STRATEGY_NAMES) -> str:
    """``name`` if it names a strategy: one of ``known``, or an external one that builds (a policy file that
    loads, a class that imports and constructs); else one SettingsError listing what is accepted."""
    if is_external(name):
        make_strategy(name)
        return str(name)
    if name in known:
        return name
    accepted = ACCEPTED.replace(", ".join(STRATEGY_NAMES), ", ".join(known), 1)
    raise SettingsError(f"unknown strategy '{name}'{did_you_mean(name, known)}; choose one of: {accepted}")


def file_label(name: str) -> str:
    """A strategy's name as a file name: ``rl:path/to/questioner.toml`` is ``rl-questioner``, ``pkg.mod:Class``
    is ``pkg.mod.Class``, a registered name is itself."""
    if str(name).startswith(RL_PREFIX):
        return f"rl-{Path(str(name)[len(RL_PREFIX):]).stem}"
    if is_plugin_spec(name):
        return plugin_file_label(name)
    return str(name)


__all__ = ["ACCEPTED", "DEFAULT_STRATEGY", "PLUGIN_FORM", "RL_PREFIX", "STRATEGIES", "STRATEGY_NAMES", "TURNS_SUFFIX",
           "DecisionTheoreticStrategy",
           "Strategy", "check_strategy_name", "file_label", "is_external", "is_plugin_spec", "make_strategy"]
