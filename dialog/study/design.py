"""The study's design: condition orders (a balanced Latin square, Williams 1949) and seeds from the study seed.

A Williams square balances both the position of each condition and which
condition follows which (first-order carry-over). For n conditions it has n
rows when n is even and 2n rows (the square and its mirror) when n is odd;
participant k takes row k mod the number of rows, so the orders are balanced
whenever the number of participants is a multiple of it.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np


def williams_rows(n: int) -> list[tuple[int, ...]]:
    """The rows of a Williams design for ``n`` conditions (indices 0..n-1)."""
    if n < 1:
        raise ValueError(f"a Latin square needs at least one condition, got {n}")
    first, low, high = [0], 1, n - 1
    while len(first) < n:
        first.append(low)
        low += 1
        if len(first) < n:
            first.append(high)
            high -= 1
    rows = [tuple((value + shift) % n for value in first) for shift in range(n)]
    if n % 2 == 1 and n > 1:
        rows += [tuple(reversed(row)) for row in rows]
    return rows


def assigned_orders(study) -> dict[str, tuple[str, ...]]:
    """Each participant's order of condition names: given in the study file, or from the Williams design."""
    if study.ordering == "given":
        return dict(study.given_orders)
    names = [c.name for c in study.conditions]
    rows = williams_rows(len(names))
    return {participant: tuple(names[i] for i in rows[k % len(rows)])
            for k, participant in enumerate(study.participants)}


def session_seed(study, participant: str, condition: str) -> int:
    """The seed of one participant's session under one condition, derived from the study seed alone. The practice
    round has a seed of its own (spawn key (k,), the conditions' are (k, j)): no condition's seed, and so no
    condition's transcript, depends on whether the study has a practice round."""
    k = study.participants.index(participant)
    if condition == "practice" and getattr(study, "practice", None) is not None:
        return int(np.random.SeedSequence(study.seed, spawn_key=(k,)).generate_state(1)[0])
    j = [c.name for c in study.conditions].index(condition)
    return int(np.random.SeedSequence(study.seed, spawn_key=(k, j)).generate_state(1)[0])


def questionnaire_rng(study, participant: str, condition: str) -> np.random.Generator:
    """The generator a simulated participant answers the questionnaire with."""
    k = study.participants.index(participant)
    j = [c.name for c in study.conditions].index(condition)
    return np.random.default_rng(np.random.SeedSequence(study.seed, spawn_key=(k, j, 1)))


@dataclass(frozen=True)
class Balance:
    """How often each condition sits at each position, and each ordered pair is adjacent, over some orders."""

    positions: dict  # (condition, position from 1) -> count
    pairs: dict  # (before, after) -> count
    participants: int

    @property
    def positions_balanced(self) -> bool:
        return len(set(self.positions.values())) <= 1

    @property
    def carryover_balanced(self) -> bool:
        return len(set(self.pairs.values())) <= 1

    @property
    def balanced(self) -> bool:
        return self.positions_balanced and self.carryover_balanced


def balance(orders, conditions) -> Balance:
    """The balance of a set of orders (each a sequence of condition names) over ``conditions``."""
    orders = [tuple(order) for order in orders]
    positions = Counter({(c, p): 0 for c in conditions for p in range(1, len(conditions) + 1)})
    pairs = Counter({(a, b): 0 for a in conditions for b in conditions if a != b})
    for order in orders:
        positions.update((name, position) for position, name in enumerate(order, start=1))
        pairs.update(zip(order, order[1:]))
    return Balance(dict(positions), dict(pairs), len(orders))
