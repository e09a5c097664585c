"""Regression suites as TOML files (``dialog/suites/NAME.toml``), validated with clear messages.

A suite names a task, the strategies to compare, the conditions (budget, turns,
change rate), how many training data sets, the checkpoints at which accuracy is
compared, and the thesis findings to test. See ``dialog/suites/README.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from dialog.experiments.kitchens import suite_kitchens
from dialog.experiments.registry import kind_names
from dialog.settings import check_budget_pays_for_a_question
from learning import datafiles
from learning.actions import DEFAULT_COSTS
from learning.datafiles import check_keys, flag, integer, number, numbers, read_toml, section, tables, text, texts
from learning.errors import DataFileError, SettingsError, did_you_mean
from learning.limits import check_limit, maximum
from learning.significance import ALTERNATIVES

SUITE_DIR = Path(__file__).resolve().parents[1] / "suites"
KINDS = ("episodes", "feature-selection", "recipes")
AXES = ("questions", "turns", "demonstrations", "seconds")
SUITE_FIELDS = ("name", "description", "analysis", "kind", "task", "kitchen", "strategies", "datasets", "seeds",
                "checkpoints", "axis", "costs", "teacher", "options", "dataset", "data_seed", "condition", "finding",
                "objects_per_scene", "state_schedule", "kitchens")
# a suite that extends another (issue 39's pre-registered run): the other's suite with more strategies and findings,
# and (issue 52's studies across kitchens) in another kitchen, with only some of its conditions
EXTENSION_FIELDS = ("extends", "name", "description", "analysis", "add_strategies", "finding", "kitchen",
                    "kitchens", "only_conditions")
CONDITION_FIELDS = ("name", "budget", "turns", "change_every")
# seconds: embodied costs' time allocation (turns is then the cap); objects_per_scene: the scene size (thesis §6.5)
# teacher: the scripted teacher's options for this condition, over the suite's [teacher] (a sweep of them)
# until_budget_spent: the thesis's chapter-6 ending (the episode ends once the budget is spent; turns is the bound)
# When an object with ordered states (prepare-lunch's pasta) is in which state (docs/open-settings.md): drawn in
# the state matching the share of the allocation's scenes already shown, or at random at every new scene.
STATE_SCHEDULES = ("episode-clock", "per-scene")
# state_schedule: when a prepare-lunch object is in which state (docs/open-settings.md; dialog.experiments.pools)
CONDITION_OPTIONAL = ("seconds", "objects_per_scene", "teacher", "until_budget_spent", "state_schedule")
FINDING_FIELDS = ("id", "text", "condition", "at", "better", "than", "alternative", "than_at", "margin")
TEACHER_KINDS = ("scripted", "oracle")
TEACHER_RATES = ("mislabel_rate", "dont_know_rate", "feature_quality", "feature_recall", "feature_noise",
                 "feature_dont_know_rate")
PLAN_FIELDS = ("pools", "pool_size", "test_size", "objects_per_scene")
FEATURE_OPTIONS = ("samples", "users", "relevant_features", "user_model")
USER_MODEL_FIELDS = ("keep_relevant", "add_irrelevant", "ignore_robot", "ignore_irrelevant_object", "ignore_relevant")


class SuiteError(DataFileError):
    """A suite file is missing, malformed, or asks for something that does not exist."""


@dataclass(frozen=True)
class Condition:
    name: str
    budget: float
    turns: int
    change_every: int
    seconds: float | None = None  # embodied costs (thesis §8.2.2): the allocation in seconds; turns is the cap
    objects_per_scene: int | None = None  # scene size of the episodes (None: the task's interactive default)
    teacher: tuple = ()  # ((option, value), ...): the scripted teacher's options here, over the suite's [teacher]
    until_budget_spent: bool = False  # end once the budget is spent (thesis ch. 6); ``turns`` is the safety bound
    state_schedule: str = "episode-clock"  # or "per-scene" (docs/open-settings.md; dialog.experiments.pools)

    def scene_size(self, task_default: int) -> int:
        """How many objects each scene of this condition holds."""
        return task_default if self.objects_per_scene is None else self.objects_per_scene


@dataclass(frozen=True)
class Finding:
    """A claim from the thesis to test: ``better`` beats each of ``than`` at checkpoint ``at``."""

    id: str
    text: str
    condition: str
    at: int
    better: str
    than: tuple[str, ...]
    alternative: str = "greater"
    than_at: int | None = None  # recipes suites: compare with ``than`` at this checkpoint instead of ``at``
    margin: float = 0.0         # ``better`` + margin beats ``than``: non-inferiority (issue 40: episodes suites too)


@dataclass(frozen=True)
class Suite:
    name: str
    description: str
    kind: str
    task: str
    kitchen: str
    strategies: tuple[str, ...]
    conditions: tuple[Condition, ...]
    datasets: int
    seeds: tuple[int, ...]
    checkpoints: tuple[int, ...]
    axis: str
    costs: dict
    teacher: dict
    findings: tuple[Finding, ...] = ()
    options: dict = field(default_factory=dict)
    path: str = ""
    dataset: dict = field(default_factory=dict)  # overrides of the task's data-set plan ([dataset] table)
    analysis: str = ""  # where the written analysis of the findings lives (shown in the report)
    data_seed: int = 0  # the seed the data sets are rendered from (0: the data of every stored baseline)
    weights: dict = field(default_factory=dict)  # strategy name -> user's DT weights (regress --weights NAME=FILE)
    kitchens: tuple[str, ...] = ()  # an episodes suite run in each of these (dialog/experiments/kitchens.py)

    @property
    def plan_options(self) -> tuple:
        """The ``[dataset]`` table as a hashable ((name, value), ...) for ``pools.load_pools``."""
        return tuple(sorted(self.dataset.items()))

    def with_overrides(self, strategies=None, seeds=None, budget=None, datasets=None, data_seed=None,
                       embodied_seconds=None) -> Suite:
        """The suite with command-line overrides applied; ``embodied_seconds`` gives every condition without a
        ``seconds`` allocation that many seconds (regress --embodied-costs)."""
        suite = self
        if embodied_seconds is not None:
            if suite.kind != "episodes":
                raise SuiteError(f"--embodied-costs applies to episodes suites; suite '{suite.name}' is of kind "
                                 f"'{suite.kind}'")
            suite = replace(suite, conditions=tuple(c if c.seconds is not None else
                                                    replace(c, seconds=float(embodied_seconds))
                                                    for c in suite.conditions))
        if data_seed is not None:
            if isinstance(data_seed, bool) or not isinstance(data_seed, int) or data_seed < 0:
                raise SuiteError(f"data seed must be a whole number >= 0, got {data_seed!r}")
            if suite.kind == "recipes":
                raise SuiteError(f"--data-seed: suite '{suite.name}' is of kind 'recipes', which renders no data "
                                 "sets; it applies to episodes and feature-selection suites")
            suite = replace(suite, data_seed=data_seed)
        if strategies:
            suite = replace(suite, strategies=tuple(strategies), findings=tuple(
                f for f in suite.findings if f.better in strategies and set(f.than) <= set(strategies)))
        if seeds:
            _check_seeds(seeds, "--seeds", SettingsError)
            suite = replace(suite, seeds=tuple(seeds))
        if budget is not None:
            check_limit("budget", budget, "--budget")
            suite = replace(suite, conditions=tuple(replace(c, budget=float(budget)) for c in suite.conditions))
        if datasets:
            check_limit("datasets", datasets, "--datasets")
            suite = replace(suite, datasets=int(datasets))
        return suite

    def with_weights(self, weights: dict) -> Suite:
        """The suite with a DT strategy per ``{name: user weights}`` added after its own strategies."""
        if not weights:
            return self
        if self.kind != "episodes":
            raise SuiteError(f"--weights adds a DT strategy to an episodes suite; suite '{self.name}' is of kind "
                             f"'{self.kind}'")
        clash = [name for name in weights if name in self.strategies]
        if clash:
            raise SuiteError(f"--weights: the name '{clash[0]}' is already a strategy of suite '{self.name}' "
                             f"({', '.join(self.strategies)}); choose another name")
        return replace(self, strategies=(*self.strategies, *weights), weights={**self.weights, **weights})


def suite_names() -> list[str]:
    return sorted(p.stem for p in SUITE_DIR.glob("*.toml"))


def _read(path: Path) -> dict:
    try:
        return read_toml(path, "suite")
    except DataFileError as error:
        raise SuiteError(str(error)) from None


def load_suite(name_or_path: str | Path, known_strategies=None) -> Suite:
    """Load and validate a suite by name (``dialog/suites/NAME.toml``) or path."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = SUITE_DIR / f"{name_or_path}.toml"
        if not path.exists():
            raise SuiteError(f"unknown suite '{name_or_path}'{did_you_mean(str(name_or_path), suite_names())}; "
                             f"available: {', '.join(suite_names())}")
    table = _read(path)
    where = str(path)
    try:
        if "extends" in table:
            table = _extended(table, where)
        return _suite(table, where, known_strategies)
    except SuiteError:
        raise
    except DataFileError as error:
        raise SuiteError(str(error)) from None


def _extended(table: dict, where: str) -> dict:
    """``extends = "NAME"``: suite NAME's table with this file's name, description and analysis, its strategies
    followed by ``add_strategies`` and its findings by this file's. It may name another ``kitchen`` (a name or a
    kitchen file's path) and keep ``only_conditions`` (with the base's findings on them); nothing else can change
    (the same conditions, data, costs and checkpoints), so in the base's kitchen its episodes are the base's."""
    check_keys(table, where, required=("extends", "name"), optional=EXTENSION_FIELDS)
    base_name = text(table, "extends", where)
    if base_name not in suite_names():
        raise SuiteError(f"{where}: extends '{base_name}', which is not a suite{did_you_mean(base_name, suite_names())}"
                         f"; available: {', '.join(suite_names())}")
    base = _read(SUITE_DIR / f"{base_name}.toml")
    if "extends" in base:
        raise SuiteError(f"{where}: extends '{base_name}', which itself extends another suite; extend the base suite")
    added = texts(table, "add_strategies", where, (), nonempty=False)
    repeated = [s for s in added if s in base.get("strategies", [])]
    if repeated:
        raise SuiteError(f"{where}: add_strategies repeats {repeated}, already in suite '{base_name}'")
    merged = {**base, **{k: table[k] for k in ("name", "description", "analysis", "kitchen", "kitchens")
                         if k in table}}
    if "kitchens" in table:
        merged.pop("kitchen", None)
    merged["strategies"] = [*base.get("strategies", []), *added]
    merged["finding"] = [*base.get("finding", []), *table.get("finding", [])]
    if "only_conditions" in table:
        kept = texts(table, "only_conditions", where, nonempty=True)
        names = [c.get("name") for c in base.get("condition", [])]
        unknown = [name for name in kept if name not in names]
        if unknown:
            raise SuiteError(f"{where}: only_conditions names {unknown}, not conditions of suite '{base_name}'; "
                             f"its conditions: {', '.join(map(str, names))}")
        merged["condition"] = [c for c in base.get("condition", []) if c.get("name") in kept]
        merged["finding"] = [f for f in merged["finding"] if f.get("condition") in kept]
        if merged.get("axis") != "seconds":  # the checkpoints the kept conditions reach (they only read curves)
            longest = max((c.get("turns", 0) for c in merged["condition"]), default=0)
            merged["checkpoints"] = [c for c in base.get("checkpoints", []) if not isinstance(c, int) or c <= longest]
    return merged


def _suite(table: dict, where: str, known_strategies) -> Suite:
    check_keys(table, where, required=("name", "strategies", "checkpoints"), optional=SUITE_FIELDS)
    kind = text(table, "kind", where, "episodes", choices=kind_names())
    strategies = texts(table, "strategies", where, nonempty=True)
    if known_strategies is not None and kind == "episodes":
        from dialog.embodied import strategy_names_with_variants  # NAME+turns: DT ignoring embodied costs
        from learning.strategies import PLUGIN_FORM, RL_PREFIX, is_external  # rl:FILE, module:Class: kind.load

        known_strategies = strategy_names_with_variants(known_strategies)
        unknown = [s for s in strategies if s not in known_strategies and not is_external(s)]
        if unknown:
            raise SuiteError(f"{where}: unknown strategies {unknown}; known: {', '.join(known_strategies)}, "
                             f"{RL_PREFIX}FILE (a trained questioner policy) or {PLUGIN_FORM}")
    scene_size = integer(table, "objects_per_scene", where, None, low=1)
    schedule = text(table, "state_schedule", where, STATE_SCHEDULES[0], choices=STATE_SCHEDULES)
    conditions = tuple(_condition(c, f"{where} condition {i + 1}", scene_size, schedule)
                       for i, c in enumerate(tables(table, "condition", where, [])))
    if kind == "episodes" and not conditions:
        raise SuiteError(f"{where}: an episodes suite needs at least one [[condition]]")
    names = [c.name for c in conditions]
    if len(set(names)) != len(names):
        raise SuiteError(f"{where}: condition names must be unique, got {names}")
    if kind == "recipes" and "data_seed" in table:
        raise SuiteError(f"{where}: 'data_seed' is not accepted in a suite of kind 'recipes' (it renders no data sets)")
    costs = _costs(table, where)
    for condition in (c for c in conditions if c.until_budget_spent):
        try:
            check_budget_pays_for_a_question(condition.budget, costs or DEFAULT_COSTS)
        except SettingsError as error:
            raise SuiteError(f"{where} condition '{condition.name}': {error}") from None
    findings = tuple(_finding(f, kind, strategies, names, f"{where} finding {i + 1}")
                     for i, f in enumerate(tables(table, "finding", where, [])))
    seeds = numbers(table, "seeds", where, (0,), whole=True, low=0)
    _check_seeds(seeds, f"{where}: seeds", SuiteError)
    checkpoints = numbers(table, "checkpoints", where, whole=True, low=0)
    _check_checkpoints(checkpoints, kind, table.get("axis", "questions"), conditions, where)
    kitchens = suite_kitchens(table, kind, where)
    return Suite(
        name=datafiles.name(table, "name", where, what="suite name"),
        description=text(table, "description", where, "", nonempty=False),
        kind=kind, task=text(table, "task", where, "pack-lunchbox"),
        kitchen=kitchens[0] if kitchens else text(table, "kitchen", where, "kitchen-1"),
        strategies=strategies, conditions=conditions,
        datasets=integer(table, "datasets", where, 5, low=1, high=maximum("datasets")),
        seeds=seeds, checkpoints=checkpoints,
        axis=text(table, "axis", where, "questions", choices=AXES), costs=costs,
        teacher=_teacher(table, where), findings=findings, options=_options(table, kind, where), path=where,
        dataset=_plan(table, where), analysis=text(table, "analysis", where, "", nonempty=False),
        data_seed=integer(table, "data_seed", where, 0, low=0), kitchens=kitchens,
    )


def _condition(table: dict, where: str, objects_per_scene: int | None = None,
               state_schedule: str = "episode-clock") -> Condition:
    """One [[condition]]; ``objects_per_scene`` and ``state_schedule`` are the suite's, which a condition may
    override."""
    check_keys(table, where, required=CONDITION_FIELDS, optional=CONDITION_OPTIONAL)
    return Condition(datafiles.name(table, "name", where, what="condition name"),
                     number(table, "budget", where, low=0.0, high=maximum("budget")),
                     integer(table, "turns", where, low=1, high=maximum("turns")),
                     integer(table, "change_every", where, low=1),
                     number(table, "seconds", where, None, above=0.0, high=maximum("seconds")),
                     integer(table, "objects_per_scene", where, objects_per_scene, low=1),
                     tuple(sorted(_teacher(table, where).items())), _until_budget_spent(table, where),
                     text(table, "state_schedule", where, state_schedule, choices=STATE_SCHEDULES))


def _until_budget_spent(table: dict, where: str) -> bool:
    """A condition's ``until_budget_spent``: true or false (default false); not with a seconds allocation."""
    value = flag(table, "until_budget_spent", where, False)
    if value and "seconds" in table:
        raise SuiteError(f"{where}: 'until_budget_spent' ends an episode on its budget, 'seconds' on its time; "
                         "give one of them")
    return value


def _check_seeds(seeds, label: str, error: type[DataFileError] | type[SettingsError]) -> None:
    """Each seed once (a seed given twice runs the same episodes twice), at most the limit of seeds."""
    repeated = sorted({seed for seed in seeds if list(seeds).count(seed) > 1})
    if repeated:
        raise error(f"{label}: seed {repeated[0]} is given twice; give each seed once")
    if len(seeds) > maximum("seeds"):
        raise error(f"{label}: {len(seeds)} seeds are beyond the limit of {maximum('seeds')} seeds in one run "
                    "(learning/data/limits.toml)")


def _check_checkpoints(checkpoints, kind: str, axis, conditions: tuple[Condition, ...], where: str) -> None:
    """Checkpoints in increasing order, at most the limit of them; an episodes suite's last one within the
    longest condition (its turns, or its seconds on the seconds axis)."""
    if any(later <= earlier for earlier, later in zip(checkpoints, checkpoints[1:])):
        raise SuiteError(f"{where}: 'checkpoints' must be in increasing order, each once, got {list(checkpoints)}")
    if len(checkpoints) > maximum("checkpoints"):
        raise SuiteError(f"{where}: {len(checkpoints)} checkpoints are beyond the limit of {maximum('checkpoints')} "
                         "(learning/data/limits.toml)")
    if kind != "episodes" or not conditions or not checkpoints:
        return
    if axis == "seconds":
        if any(c.seconds is None for c in conditions):
            return  # the seconds come from --embodied-costs' default allocation
        longest, unit = max(float(c.seconds) for c in conditions), "seconds"  # type: ignore[arg-type]
    else:
        longest, unit = max(c.turns for c in conditions), "turns"
    if checkpoints[-1] > longest:
        raise SuiteError(f"{where}: checkpoint {checkpoints[-1]} lies beyond every condition (the longest has "
                         f"{longest:g} {unit}); give checkpoints within it")


def _finding(table: dict, kind: str, strategies: tuple, conditions: list, where: str) -> Finding:
    check_keys(table, where, required=("id", "text", "at", "better", "than"), optional=FINDING_FIELDS)
    at = integer(table, "at", where, low=0)
    default_condition = f"n{at}" if kind == "feature-selection" else ""
    finding = Finding(text(table, "id", where), text(table, "text", where),
                      text(table, "condition", where, default_condition), at, text(table, "better", where),
                      texts(table, "than", where, nonempty=True),
                      text(table, "alternative", where, "greater", choices=ALTERNATIVES),
                      *_recipe_finding_extras(table, kind, where))
    missing = [s for s in (finding.better, *finding.than) if s not in strategies]
    if missing:
        raise SuiteError(f"{where}: strategies {missing} are not in the suite's strategies")
    if conditions and finding.condition not in conditions:
        raise SuiteError(f"{where}: condition '{finding.condition}' is not one of {conditions}")
    return finding


def _costs(table: dict, where: str) -> dict:
    """The [costs] table: every action kind (label, demo, feature, none) with a finite cost >= 0."""
    costs = section(table, "costs", where, None)
    if costs is None:
        return {}
    check_keys(costs, f"{where} [costs]", required=tuple(DEFAULT_COSTS))
    for kind in DEFAULT_COSTS:
        number(costs, kind, f"{where} [costs]", low=0.0)
    return {kind: costs[kind] for kind in DEFAULT_COSTS}  # as written (1 stays 1 in transcripts and baselines)


def _teacher(table: dict, where: str) -> dict:
    """The [teacher] table: kind (scripted or oracle) and the scripted teacher's rates, each 0..1."""
    return teacher_options(section(table, "teacher", where, {}), f"{where} [teacher]")


def teacher_options(teacher: dict, here: str) -> dict:
    """A scripted teacher's options (a suite's [teacher], the Gymnasium environment's ``teacher``), checked."""
    check_keys(teacher, here, optional=("kind", *TEACHER_RATES))
    result = {"kind": text(teacher, "kind", here, choices=TEACHER_KINDS)} if "kind" in teacher else {}
    return result | {key: number(teacher, key, here, low=0.0, high=1.0) for key in TEACHER_RATES if key in teacher}


def _plan(table: dict, where: str) -> dict:
    """The [dataset] table: overrides of the task's data-set plan, whole numbers >= 1."""
    plan, here = section(table, "dataset", where, {}), f"{where} [dataset]"
    check_keys(plan, here, optional=PLAN_FIELDS)
    return {key: integer(plan, key, here, low=1) for key in plan}


def _options(table: dict, kind: str, where: str) -> dict:
    """[options]: none for episodes; the study's settings for feature-selection; recipes: see recipe_suite."""
    options, here = section(table, "options", where, {}), f"{where} [options]"
    if kind == "episodes":
        check_keys(options, here)
    elif kind == "feature-selection":
        check_keys(options, here, optional=FEATURE_OPTIONS)
        integer(options, "samples", here, 10, low=1)
        integer(options, "users", here, 10, low=1)
        texts(options, "relevant_features", here, ())
        user_model = section(options, "user_model", here, {})
        check_keys(user_model, f"{here} user_model", optional=USER_MODEL_FIELDS)
        for key in user_model:
            number(user_model, key, f"{here} user_model", low=0.0, high=1.0)
    return dict(options)


def _recipe_finding_extras(table: dict, kind: str, where: str) -> tuple[int | None, float]:
    """``than_at`` and ``margin`` of a finding: only a recipes suite compares across checkpoints; a margin
    (non-inferiority: ``better`` + margin beats ``than``) is accepted by every kind."""
    margin = number(table, "margin", where, 0.0, low=0.0)
    if kind != "recipes":
        if "than_at" in table:
            raise SuiteError(f"{where}: 'than_at' is only accepted in a suite of kind 'recipes'")
        return None, margin
    return integer(table, "than_at", where, None, low=0), margin
