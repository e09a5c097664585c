"""Allocations a learned questioner trains across (issue 40, item 4; beyond the thesis).

The thesis trains DT-task-env on one allocation (budget 15, 30 turns, §7.4.1) and tests it on others. A
policy that is to carry across allocations trains on a distribution of them and sees its episode's
allocation in its observation (learning/rl/observation.py, ``allocation_features``). The distribution lives
in a data file (dialog/data/rl-allocations.toml): ranges for the budget (drawn log-uniformly, so 15-50 is as
likely as 150-500), the turns and the scene changes, and suites whose conditions are held out of training.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from learning.datafiles import check_keys, numbers, read_toml, section, texts
from learning.errors import DataFileError, SettingsError
from learning.limits import maximum

DEFAULT_FILE = Path(__file__).resolve().parent.parent / "data" / "rl-allocations.toml"
STREAM = 0xA110C  # the allocation's own stream beside the episode's (dialog/manager.episode_generators)
MAX_DRAWS = 1000  # a draw that hits a held-out allocation is drawn again, at most this often
RANGES = ("budget", "turns", "change_every")


@dataclass(frozen=True, order=True)
class Allocation:
    """One episode's budget (cost units), turns and turns per scene."""

    budget: float
    turns: int
    change_every: int

    def record(self) -> dict:
        return {"budget": self.budget, "turns": self.turns, "change_every": self.change_every}


@dataclass(frozen=True)
class AllocationRanges:
    """Inclusive ranges to draw an episode's allocation from, and the allocations never drawn."""

    budget: tuple[int, int]
    turns: tuple[int, int]
    change_every: tuple[int, int]
    held_out: frozenset[Allocation] = frozenset()

    def __post_init__(self) -> None:
        limits = {"budget": maximum("budget"), "turns": maximum("turns"), "change_every": maximum("turns")}
        for name in RANGES:
            low_high = getattr(self, name)
            if (not isinstance(low_high, tuple) or len(low_high) != 2
                    or any(isinstance(v, bool) or not isinstance(v, int | np.integer) for v in low_high)
                    or not 1 <= low_high[0] <= low_high[1] <= limits[name]):
                raise SettingsError(f"allocations: {name} must be two whole numbers [low, high] with "
                                    f"1 <= low <= high <= {limits[name]}, got {low_high!r}")
        if self.change_every[0] > self.turns[1]:
            raise SettingsError(f"allocations: change_every's low end {self.change_every[0]} is above the most turns "
                                f"{self.turns[1]}; a scene cannot last longer than its episode")

    def draw(self, seed: int) -> Allocation:
        """The allocation of the episode with this seed: the same seed, the same allocation, in any process."""
        rng = np.random.default_rng([int(seed), STREAM])
        low, high = np.log(self.budget[0]), np.log(self.budget[1])
        for _ in range(MAX_DRAWS):
            turns = int(rng.integers(self.turns[0], self.turns[1] + 1))
            drawn = Allocation(budget=float(round(float(np.exp(rng.uniform(low, high))))), turns=turns,
                               change_every=int(rng.integers(self.change_every[0],
                                                             min(self.change_every[1], turns) + 1)))
            if drawn not in self.held_out:
                return drawn
        raise SettingsError(f"allocations: {MAX_DRAWS} draws in a row were held-out allocations; widen the ranges")

    def record(self) -> dict:
        """The ranges as provenance text for a policy file."""
        held = ", ".join(f"{a.budget:g}/{a.turns}/{a.change_every}" for a in sorted(self.held_out)) or "none"
        return {f"allocations_{name}": list(getattr(self, name)) for name in RANGES} | {"allocations_held_out": held}


def ranges_from(value) -> AllocationRanges:
    """The environment's ``allocations`` option: AllocationRanges, or a dict of [low, high] per range."""
    if isinstance(value, AllocationRanges):
        return value
    if not isinstance(value, dict) or set(value) - set(RANGES) or not set(RANGES) <= set(value):
        raise SettingsError(f"allocations must be a dict with the keys {', '.join(RANGES)}, each [low, high], "
                            f"got {value!r}")
    return AllocationRanges(*(tuple(value[name]) if isinstance(value[name], list | tuple) else value[name]
                              for name in RANGES))


def load_allocations(path: str | Path = DEFAULT_FILE) -> AllocationRanges:
    """Read an allocations file (see dialog/data/rl-allocations.toml); anything wrong is one DataFileError."""
    from dialog.experiments.suite import load_suite

    data = read_toml(path, "allocations")
    where = str(path)
    check_keys(data, where, required=("train",), optional=("held_out",))
    train, here = section(data, "train", where), f"{where} [train]"
    check_keys(train, here, required=RANGES)
    bounds = {name: numbers(train, name, here, length=2, whole=True, low=1) for name in RANGES}
    held = section(data, "held_out", where, {})
    check_keys(held, f"{where} [held_out]", optional=("suites",))
    held_out = set()
    for suite_name in texts(held, "suites", f"{where} [held_out]", default=()):
        for condition in load_suite(suite_name).conditions:
            held_out.add(Allocation(float(condition.budget), int(condition.turns), int(condition.change_every)))
    try:
        return AllocationRanges(*(tuple(int(v) for v in bounds[name]) for name in RANGES), frozenset(held_out))
    except SettingsError as error:
        raise DataFileError(f"{here}: {str(error).removeprefix('allocations: ')}") from None
