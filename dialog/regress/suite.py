"""Regression suites as TOML files (``dialog/suites/NAME.toml``), validated with clear messages.

A suite names a task, the strategies to compare, the conditions (budget, turns,
change rate), how many training data sets, the checkpoints at which accuracy is
compared, and the thesis findings to test. See ``dialog/suites/README.md``.
"""

from __future__ import annotations

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

SUITE_DIR = Path(__file__).resolve().parents[1] / "suites"
KINDS = ("episodes", "feature-selection", "recipes")
AXES = ("questions", "turns", "demonstrations")


class SuiteError(ValueError):
    """A suite file is missing, malformed, or asks for something that does not exist."""


@dataclass(frozen=True)
class Condition:
    name: str
    budget: float
    turns: int
    change_every: int


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
    margin: float = 0.0         # recipes suites: ``better`` + margin beats ``than`` (non-inferiority)


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

    @property
    def plan_options(self) -> tuple:
        """The ``[dataset]`` table as a hashable ((name, value), ...) for :func:`dialog.regress.pools.load_pools`."""
        return tuple(sorted(self.dataset.items()))

    def with_overrides(self, strategies=None, seeds=None, budget=None, datasets=None) -> Suite:
        """The suite with command-line overrides applied."""
        suite = self
        if strategies:
            suite = replace(suite, strategies=tuple(strategies), findings=tuple(
                f for f in suite.findings if f.better in strategies and set(f.than) <= set(strategies)))
        if seeds:
            suite = replace(suite, seeds=tuple(seeds))
        if budget is not None:
            suite = replace(suite, conditions=tuple(replace(c, budget=float(budget)) for c in suite.conditions))
        if datasets:
            suite = replace(suite, datasets=int(datasets))
        return suite


def suite_names() -> list[str]:
    return sorted(p.stem for p in SUITE_DIR.glob("*.toml"))


def _need(table: dict, key: str, kind, where: str):
    if key not in table:
        raise SuiteError(f"{where}: missing '{key}'")
    value = table[key]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise SuiteError(f"{where}: '{key}' must be {getattr(kind, '__name__', kind)}, got {value!r}")
    return value


def load_suite(name_or_path: str | Path, known_strategies=None) -> Suite:
    """Load and validate a suite by name (``dialog/suites/NAME.toml``) or path."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = SUITE_DIR / f"{name_or_path}.toml"
        if not path.exists():
            raise SuiteError(f"unknown suite '{name_or_path}'; available: {', '.join(suite_names())}")
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SuiteError(f"{path}: no such file") from None
    except tomllib.TOMLDecodeError as error:
        raise SuiteError(f"{path}: not valid TOML ({error})") from None
    where = str(path)
    kind = table.get("kind", "episodes")
    if kind not in KINDS:
        raise SuiteError(f"{where}: kind '{kind}' is not one of {', '.join(KINDS)}")
    strategies = tuple(_need(table, "strategies", list, where))
    if known_strategies is not None and kind == "episodes":
        unknown = [s for s in strategies if s not in known_strategies]
        if unknown:
            raise SuiteError(f"{where}: unknown strategies {unknown}; known: {', '.join(known_strategies)}")
    conditions = tuple(
        Condition(_need(c, "name", str, f"{where} condition {i + 1}"), _need(c, "budget", float, f"{where} "
                  f"condition {i + 1}"), _need(c, "turns", int, f"{where} condition {i + 1}"),
                  _need(c, "change_every", int, f"{where} condition {i + 1}"))
        for i, c in enumerate(table.get("condition", []))
    )
    if kind == "episodes" and not conditions:
        raise SuiteError(f"{where}: an episodes suite needs at least one [[condition]]")
    names = [c.name for c in conditions]
    if len(set(names)) != len(names):
        raise SuiteError(f"{where}: condition names must be unique, got {names}")
    axis = table.get("axis", "questions")
    if axis not in AXES:
        raise SuiteError(f"{where}: axis '{axis}' is not one of {', '.join(AXES)}")
    findings = []
    for i, f in enumerate(table.get("finding", [])):
        at = f"{where} finding {i + 1}"
        default_condition = f"n{f.get('at')}" if kind == "feature-selection" else ""
        finding = Finding(_need(f, "id", str, at), _need(f, "text", str, at), f.get("condition", default_condition),
                          _need(f, "at", int, at), _need(f, "better", str, at), tuple(_need(f, "than", list, at)),
                          f.get("alternative", "greater"), *_recipe_finding_extras(f, kind, at))
        missing = [s for s in (finding.better, *finding.than) if s not in strategies]
        if missing:
            raise SuiteError(f"{at}: strategies {missing} are not in the suite's strategies")
        if conditions and finding.condition not in names:
            raise SuiteError(f"{at}: condition '{finding.condition}' is not one of {names}")
        findings.append(finding)
    return Suite(
        name=_need(table, "name", str, where), description=table.get("description", ""), kind=kind,
        task=table.get("task", "pack-lunchbox"), kitchen=table.get("kitchen", "kitchen-1"),
        strategies=strategies, conditions=conditions, datasets=int(table.get("datasets", 5)),
        seeds=tuple(table.get("seeds", [0])), checkpoints=tuple(_need(table, "checkpoints", list, where)),
        axis=axis, costs=dict(table.get("costs", {})), teacher=dict(table.get("teacher", {})),
        findings=tuple(findings), options=dict(table.get("options", {})), path=where,
        dataset=dict(table.get("dataset", {})), analysis=str(table.get("analysis", "")),
    )


def _recipe_finding_extras(table: dict, kind: str, where: str) -> tuple[int | None, float]:
    """``than_at`` and ``margin`` of a finding: only a recipes suite compares across checkpoints."""
    if kind != "recipes":
        extra = [key for key in ("than_at", "margin") if key in table]
        if extra:
            raise SuiteError(f"{where}: '{extra[0]}' is only accepted in a suite of kind 'recipes'")
        return None, 0.0
    than_at = _need(table, "than_at", int, where) if "than_at" in table else None
    margin = _need(table, "margin", float, where) if "margin" in table else 0.0
    if margin < 0:
        raise SuiteError(f"{where}: 'margin' must be >= 0, got {margin}")
    return than_at, margin
