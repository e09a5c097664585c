"""Argument types and option groups shared by several subcommands."""

from __future__ import annotations

import argparse

from dialog.settings import DEFAULTS, EpisodeSettings


def _number(text: str, kind, what: str):
    """``text`` read as ``kind`` (int or float), finite; argparse's error names what was expected."""
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got '{text}'") from None
    if kind is float and value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"expected {what}, got '{text}'")
    return value


def _at_least(kind, what: str, minimum: float, too_small: str):
    """An argparse type: a finite ``kind`` number of at least ``minimum`` (``too_small`` says why not)."""
    def parse(text: str):
        value = _number(text, kind, what)
        if value < minimum:
            raise argparse.ArgumentTypeError(too_small.format(value=value))
        return value
    return parse


positive_int = _at_least(int, "a whole number", 1, "expected a whole number of at least 1, got {value}")
budget = _at_least(float, "a number of cost units", 0, "the budget can't be negative, got {value:g}")
seconds = _at_least(float, "a number of seconds", 0, "expected zero or more seconds, got {value:g}")


def positive_seconds(text: str) -> float:
    value = seconds(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {value:g}")
    return value


def add_episode_options(parser: argparse.ArgumentParser, strategies, default_strategy: str,
                        defaults: EpisodeSettings = DEFAULTS) -> None:
    """--seed --turns --budget --change-every --strategy --task --kitchen, their defaults read from ``defaults``."""
    parser.add_argument("--seed", type=int, default=defaults.seed,
                        help=f"one seed for every random choice (default {defaults.seed})")
    parser.add_argument("--turns", type=positive_int, default=defaults.turns,
                        help=f"time allocation T in turns (default {defaults.turns})")
    parser.add_argument("--budget", type=budget, default=defaults.budget,
                        help=f"question budget B in cost units (default {defaults.budget:g})")
    parser.add_argument("--change-every", type=positive_int, default=defaults.change_every,
                        help=f"a new scene every r turns (default {defaults.change_every})")
    parser.add_argument("--strategy", default=default_strategy, choices=strategies,
                        help=f"questioning strategy (default {default_strategy})")
    parser.add_argument("--task", default=defaults.task, help=f"task data file name (default {defaults.task})")
    parser.add_argument("--kitchen", default=defaults.kitchen,
                        help=f"kitchen data file name (default {defaults.kitchen})")
