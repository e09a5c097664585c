"""The committed rule that picks a hand-set DT preset's weights on calibration data (issue 39; docs/calibration.md).

A rule file (``dialog/data/calibration/dt-weights.toml``) names the presets to calibrate, for each one weight
and a grid of values for it (the other weights kept as the preset's ``base`` has them), the conditions (suite
and condition name, as the suites define them) and the calibration data: data seeds >= 100, which no
reported table uses. :func:`calibrate` plays every grid value on every condition, data seed, data set and
episode seed, and picks per preset the value with the highest mean final accuracy (ties to the smaller).
``scripts/calibrate_dt.py`` is the command.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from dialog.experiments.pools import load_pools
from dialog.experiments.provenance import git_commit
from dialog.experiments.runner import episode_specs, run_locally
from dialog.experiments.suite import Suite, SuiteError, load_suite
from dialog.user_weights import UserWeights
from learning.datafiles import check_keys, integer, number, numbers, read_toml, tables, text
from learning.decision.features import FEATURE_NAMES
from learning.decision.weights import PRESETS, WEIGHTS_DIRECTORY
from learning.decision.weights_file import DecisionWeights, load_weights, save_weights
from learning.errors import DataFileError

CALIBRATION_DIR = Path(__file__).resolve().parents[1] / "data" / "calibration"
RULE_FILE = CALIBRATION_DIR / "dt-weights.toml"
FIRST_CALIBRATION_SEED = 100  # data seeds below this one are the reported tables' (0-4, and 20-29 planned)
RULE_FIELDS = ("statistic", "ties", "tie_tolerance", "data_seeds", "datasets", "seeds")
PRESET_FIELDS = ("name", "base", "feature", "grid")
CONDITION_FIELDS = ("suite", "name")
CONDITION_SHRINK = ("turns", "budget")  # a test rule's smaller allocation (the real rule uses the suites')


@dataclass(frozen=True)
class GridPreset:
    """One preset to calibrate: the weight ``feature`` of ``base``'s weights takes each value of ``grid``."""

    name: str
    base: str
    feature: str
    grid: tuple[float, ...]

    def weights(self, value: float) -> dict[str, float]:
        """The base preset's weights with ``feature`` set to ``value``."""
        return load_weights(WEIGHTS_DIRECTORY / f"{self.base}.toml").as_dict() | {self.feature: float(value)}

    def strategy_name(self, index: int) -> str:
        """The name grid value ``index`` plays under (in transcripts and progress lines)."""
        return f"{self.name}-grid{index}"


@dataclass(frozen=True)
class RuleCondition:
    suite: str
    name: str
    turns: int | None = None
    budget: float | None = None


@dataclass(frozen=True)
class Rule:
    path: Path
    sha256: str
    data_seeds: tuple[int, ...]
    datasets: int
    seeds: tuple[int, ...]
    tie_tolerance: float
    presets: tuple[GridPreset, ...]
    conditions: tuple[RuleCondition, ...]

    @property
    def episodes_per_value(self) -> int:
        return len(self.conditions) * len(self.data_seeds) * self.datasets * len(self.seeds)

    @property
    def episodes(self) -> int:
        return sum(len(p.grid) for p in self.presets) * self.episodes_per_value


def load_rule(path: str | Path = RULE_FILE) -> Rule:
    """Read and check a rule file; anything wrong is one DataFileError naming the file and what is accepted."""
    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"{path}: no calibration rule file there (see {RULE_FILE} for the form)")
    table, where = read_toml(path, "calibration rule"), str(path)
    check_keys(table, where, required=("rule", "preset", "condition"))
    rule = table["rule"]
    if not isinstance(rule, dict):
        raise DataFileError(f"{where}: [rule] must be a table")
    here = f"{where} [rule]"
    check_keys(rule, here, required=("data_seeds", "datasets", "seeds"), optional=RULE_FIELDS)
    text(rule, "statistic", here, "final-accuracy", choices=("final-accuracy",))
    text(rule, "ties", here, "smaller", choices=("smaller",))
    data_seeds = numbers(rule, "data_seeds", here, whole=True, low=FIRST_CALIBRATION_SEED)
    seeds = numbers(rule, "seeds", here, whole=True, low=0)
    for label, values in (("data_seeds", data_seeds), ("seeds", seeds)):
        if len(set(values)) != len(values):
            raise DataFileError(f"{here}: '{label}' gives a value twice; give each once")
    presets = tuple(_preset(p, f"{where} preset {i + 1}") for i, p in enumerate(tables(table, "preset", where,
                                                                                         nonempty=True)))
    names = [p.name for p in presets]
    if len(set(names)) != len(names):
        raise DataFileError(f"{where}: each preset once, got {names}")
    conditions = tuple(_condition(c, f"{where} condition {i + 1}")
                       for i, c in enumerate(tables(table, "condition", where, nonempty=True)))
    return Rule(path, hashlib.sha256(path.read_bytes()).hexdigest(), tuple(int(s) for s in data_seeds),
                integer(rule, "datasets", here, low=1), tuple(int(s) for s in seeds),
                number(rule, "tie_tolerance", here, 1e-9, low=0.0), presets, conditions)


def _preset(table: dict, where: str) -> GridPreset:
    check_keys(table, where, required=PRESET_FIELDS)
    name, base = text(table, "name", where, choices=PRESETS), text(table, "base", where, choices=PRESETS)
    feature = text(table, "feature", where, choices=FEATURE_NAMES)
    grid = tuple(float(v) for v in numbers(table, "grid", where))
    if list(grid) != sorted(set(grid)):
        raise DataFileError(f"{where}: 'grid' must list each value once, in increasing order, got {list(grid)}")
    return GridPreset(name, base, feature, grid)


def _condition(table: dict, where: str) -> RuleCondition:
    check_keys(table, where, required=CONDITION_FIELDS, optional=CONDITION_SHRINK)
    suite_name, name = text(table, "suite", where), text(table, "name", where)
    try:
        suite = load_suite(suite_name)
    except SuiteError as error:
        raise DataFileError(f"{where}: {error}") from None
    known = [c.name for c in suite.conditions]
    if name not in known:
        raise DataFileError(f"{where}: suite '{suite_name}' has no condition '{name}'; its conditions: "
                            f"{', '.join(known)}")
    return RuleCondition(suite_name, name, integer(table, "turns", where, None, low=1),
                         number(table, "budget", where, None, low=0.0))


def plan_suites(rule: Rule) -> list[Suite]:
    """One suite per (suite, data seed): the rule's conditions of it, every preset's grid values as strategies."""
    weights = {p.strategy_name(i): UserWeights(f"{rule.path.name}: {p.name} with {p.feature} = {value:g}",
                                               tuple(p.weights(value).items()))
               for p in rule.presets for i, value in enumerate(p.grid)}
    suites = []
    for suite_name in dict.fromkeys(c.suite for c in rule.conditions):
        suite = load_suite(suite_name)
        chosen = []
        for wanted in (c for c in rule.conditions if c.suite == suite_name):
            condition = next(c for c in suite.conditions if c.name == wanted.name)
            chosen.append(replace(condition, turns=wanted.turns or condition.turns,
                                  budget=condition.budget if wanted.budget is None else wanted.budget))
        base = replace(suite, conditions=tuple(chosen), strategies=(), findings=(), weights={},
                       datasets=rule.datasets, seeds=rule.seeds).with_weights(weights)
        suites += [replace(base, data_seed=seed) for seed in rule.data_seeds]
    return suites


@dataclass(frozen=True)
class Choice:
    """A preset's grid, the mean final accuracy and episodes of each value, and the value chosen."""

    preset: GridPreset
    accuracies: tuple[float, ...]
    episodes: tuple[int, ...]
    chosen: float


def choose(preset: GridPreset, accuracies: list[float], tolerance: float) -> float:
    """The grid value with the highest mean accuracy; those within ``tolerance`` of it go to the smallest."""
    best = max(accuracies)
    return min(value for value, mean in zip(preset.grid, accuracies) if mean >= best - tolerance)


def calibrate(rule: Rule, results_dir: Path, workers: int | None = None, progress: bool = True,
              say: Callable[[str], None] = print) -> tuple[list[Choice], dict]:
    """Play the rule's episodes and choose; returns the choices and the run's facts (episodes, seconds)."""
    started, finals = time.perf_counter(), {}
    by_condition: dict[str, list[float]] = {}  # "suite/condition": each episode's seconds (one core)
    for suite in plan_suites(rule):
        say(f"{suite.name}, data seed {suite.data_seed}: rendering or reading the data sets")
        rendering = time.perf_counter()
        load_pools(suite.task, suite.kitchen, suite.datasets, suite.plan_options, data_seed=suite.data_seed)
        specs = episode_specs(suite, results_dir / suite.name / f"data-seed-{suite.data_seed}")
        say(f"{suite.name}, data seed {suite.data_seed}: data sets ready in {time.perf_counter() - rendering:.0f} s; "
            f"{len(specs)} episodes")
        for result in run_locally(specs, workers, progress):
            finals.setdefault(result["spec"]["strategy"], []).append(float(result["accuracy"]))
            by_condition.setdefault(f"{suite.name}/{result['spec']['condition']['name']}", []).append(
                float(result["seconds"]))
    choices = []
    for preset in rule.presets:
        values = [finals.get(preset.strategy_name(i), []) for i in range(len(preset.grid))]
        accuracies = [float(np.mean(v)) if v else math.nan for v in values]
        choices.append(Choice(preset, tuple(accuracies), tuple(len(v) for v in values),
                              choose(preset, accuracies, rule.tie_tolerance)))
    episodes = sum(len(v) for v in finals.values())
    return choices, {"episodes": episodes, "seconds": round(time.perf_counter() - started, 1),
                     "episode_seconds": round(sum(sum(v) for v in by_condition.values()), 1),
                     "seconds_per_episode_by_condition": {key: round(float(np.mean(v)), 2)
                                                          for key, v in by_condition.items()}}


def chosen_weights(choice: Choice, rule: Rule, facts: dict) -> DecisionWeights:
    """The chosen weights with their provenance (the form of learning/decision/presets/*.toml)."""
    grid = "; ".join(f"{value:g}: {mean:.4f} ({n} episodes)"
                     for value, mean, n in zip(choice.preset.grid, choice.accuracies, choice.episodes))
    weights = choice.preset.weights(choice.chosen)
    provenance = {"method": "calibration rule (issue 39)", "rule_file": _shown(rule.path),
                  "rule_sha256": rule.sha256, "commit": git_commit(), "base": choice.preset.base,
                  "feature": choice.preset.feature, "chosen": choice.chosen, "grid_mean_final_accuracy": grid,
                  "data_seeds": ", ".join(map(str, rule.data_seeds)), "datasets": rule.datasets,
                  "seeds": ", ".join(map(str, rule.seeds)),
                  "conditions": ", ".join(f"{c.suite}/{c.name}" for c in rule.conditions),
                  "episodes": facts["episodes"], "wall_seconds": facts["seconds"]}
    return DecisionWeights(tuple(weights), np.array(list(weights.values())), provenance)


def write_choices(choices: list[Choice], rule: Rule, facts: dict, folder: Path) -> list[Path]:
    """One weights file per preset in ``folder`` (``NAME.toml``), each with its provenance."""
    folder.mkdir(parents=True, exist_ok=True)
    return [save_weights(folder / f"{c.preset.name}.toml", chosen_weights(c, rule, facts),
                         f"{c.preset.name}: weights chosen by the calibration rule {_shown(rule.path)} "
                         "(docs/calibration.md); written by scripts/calibrate_dt.py") for c in choices]


def _shown(path: Path) -> str:
    """A path relative to the repository when inside it (provenance that reads the same on every machine)."""
    try:
        return str(path.resolve().relative_to(CALIBRATION_DIR.parents[1]))
    except ValueError:
        return str(path)
