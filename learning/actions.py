"""The robot's candidate actions each turn and what they cost (thesis §7.3.1).

Costs come from one table: demonstration query 2, feature-subset query 2,
label query 1, no query 0 (configurable).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

ActionKind = Literal["label", "demo", "feature", "none"]
ACTION_KINDS: tuple[ActionKind, ...] = get_args(ActionKind)  # label, demo, feature, none

DEFAULT_COSTS: dict[ActionKind, float] = {"label": 1, "demo": 2, "feature": 2, "none": 0}


@dataclass(frozen=True)
class LabelQuery:
    """Point at scene object ``object_index`` and ask what it is (LQ)."""

    object_index: int
    kind: Literal["label"] = "label"


@dataclass(frozen=True)
class DemoQuery:
    """Ask the teacher to show an example of ``concept`` (DQ)."""

    concept: str
    kind: Literal["demo"] = "demo"


@dataclass(frozen=True)
class FeatureQuery:
    """Ask which features tell the concepts apart (FSQ, asked at most once)."""

    kind: Literal["feature"] = "feature"


@dataclass(frozen=True)
class NoQuery:
    """Stay quiet this turn."""

    kind: Literal["none"] = "none"


Action = LabelQuery | DemoQuery | FeatureQuery | NoQuery


@dataclass(frozen=True)
class Decision:
    """A strategy's choice and its one-sentence reason; a utility-based strategy (DT) adds ``terms``: per weighted
    feature, its share of EU(best query) - EU(no query) (``learning.decision.reasons.utility_terms``)."""

    action: Action
    explanation: str
    terms: tuple[tuple[str, float], ...] = ()


def validate_costs(costs: dict) -> dict[str, float]:
    """Check a cost table: every action kind present, non-negative numbers."""
    missing = sorted(set(DEFAULT_COSTS) - set(costs))
    unknown = sorted(set(costs) - set(DEFAULT_COSTS))
    if missing or unknown:
        raise ValueError(f"cost table needs exactly the keys {sorted(DEFAULT_COSTS)}; "
                         f"missing {missing}, unknown {unknown}")
    for kind, value in costs.items():
        if not isinstance(value, (int, float)) or isinstance(value, bool) or value < 0:
            raise ValueError(f"cost of '{kind}' must be a non-negative number, got {value!r}")
    return {kind: float(value) for kind, value in costs.items()}
