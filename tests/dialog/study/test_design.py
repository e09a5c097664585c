"""The study design: Williams squares balance positions and carry-over; seeds come from the study seed alone."""

import dataclasses
from pathlib import Path

import pytest

from dialog.study.design import assigned_orders, balance, session_seed, williams_rows
from dialog.study.studyfile import load_study

EXAMPLE = Path(__file__).resolve().parents[3] / "dialog" / "data" / "studies" / "example.toml"


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
def test_williams_rows_balance_positions_and_carryover(n):
    rows = williams_rows(n)
    assert len(rows) == (2 * n if n % 2 and n > 1 else n)  # odd n needs the mirrored square too
    assert all(sorted(row) == list(range(n)) for row in rows)
    result = balance(rows, list(range(n)))
    assert result.positions_balanced and result.carryover_balanced
    if n > 1:
        assert set(result.pairs.values()) == {len(rows) * (n - 1) // (n * (n - 1))}


def test_odd_square_alone_is_not_carryover_balanced():
    rows = williams_rows(3)[:3]  # the square without its mirror
    result = balance(rows, [0, 1, 2])
    assert result.positions_balanced and not result.carryover_balanced


def test_balance_counts_an_unbalanced_set():
    result = balance([("a", "b"), ("a", "b")], ["a", "b"])
    assert not result.positions_balanced
    assert result.positions[("a", 1)] == 2 and result.positions[("b", 1)] == 0


def test_example_orders_form_a_complete_williams_design():
    study = load_study(EXAMPLE)
    orders = assigned_orders(study)
    assert list(orders) == list(study.participants)
    assert len(set(orders.values())) == 6  # 3 conditions: six distinct orders for six participants
    assert balance(orders.values(), [c.name for c in study.conditions]).balanced


def test_participants_beyond_a_block_repeat_the_rows():
    study = dataclasses.replace(load_study(EXAMPLE), participants=tuple(f"P{i:02d}" for i in range(1, 14)))
    orders = assigned_orders(study)
    assert orders["P07"] == orders["P01"] and orders["P13"] == orders["P01"]


def test_given_orders_are_used_as_given():
    study = dataclasses.replace(load_study(EXAMPLE), ordering="given",
                                given_orders={"P01": ("active", "dt-task", "dt-small-budget")})
    assert assigned_orders(study) == {"P01": ("active", "dt-task", "dt-small-budget")}


def test_seeds_are_deterministic_distinct_and_follow_the_study_seed():
    study = load_study(EXAMPLE)
    seeds = {(p, c.name): session_seed(study, p, c.name) for p in study.participants for c in study.conditions}
    assert len(set(seeds.values())) == len(seeds)
    assert session_seed(study, "P01", "active") == seeds[("P01", "active")]
    other = dataclasses.replace(study, seed=study.seed + 1)
    assert session_seed(other, "P01", "active") != seeds[("P01", "active")]
