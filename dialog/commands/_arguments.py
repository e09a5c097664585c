"""Argument types and option groups shared by several subcommands."""

from __future__ import annotations

import argparse


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of at least 1, got {value}")
    return value


def budget(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of cost units, got '{text}'") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"the budget can't be negative, got {value}")
    return value


def seconds(text: str) -> float:
    """Zero or more seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got '{text}'") from None
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected zero or more seconds, got {value:g}")
    return value


def positive_seconds(text: str) -> float:
    value = seconds(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {value:g}")
    return value


def add_episode_options(parser: argparse.ArgumentParser, strategies, default_strategy: str) -> None:
    """--seed --turns --budget --change-every --strategy --task --kitchen --transcript."""
    parser.add_argument("--seed", type=int, default=0, help="one seed for every random choice (default 0)")
    parser.add_argument("--turns", type=positive_int, default=30, help="time allocation T in turns (default 30)")
    parser.add_argument("--budget", type=budget, default=40.0, help="question budget B in cost units (default 40)")
    parser.add_argument("--change-every", type=positive_int, default=5,
                        help="a new scene every r turns (default 5)")
    parser.add_argument("--strategy", default=default_strategy, choices=strategies,
                        help=f"questioning strategy (default {default_strategy})")
    parser.add_argument("--task", default="pack-lunchbox", help="task data file name (default pack-lunchbox)")
    parser.add_argument("--kitchen", default="kitchen-1", help="kitchen data file name (default kitchen-1)")
