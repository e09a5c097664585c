"""Questioning strategies: each looks at the learning state and returns one Decision.

``make_strategy(name)`` builds one by name; ``STRATEGY_NAMES`` lists them all.
"""

from __future__ import annotations

from learning.strategies.active import ActiveStrategy
from learning.strategies.base import Strategy
from learning.strategies.passive import PassiveStrategy

STRATEGIES: dict[str, type[Strategy]] = {
    "passive": PassiveStrategy,
    "active": ActiveStrategy,
}
STRATEGY_NAMES = tuple(STRATEGIES)


def make_strategy(name: str) -> Strategy:
    """The strategy called ``name``; a clear error lists the accepted names."""
    key = name.strip().lower()
    if key not in STRATEGIES:
        raise ValueError(f"unknown strategy '{name}'; choose one of: {', '.join(STRATEGY_NAMES)}")
    return STRATEGIES[key]()


__all__ = ["STRATEGIES", "STRATEGY_NAMES", "Strategy", "make_strategy"]
