"""A user's weights file as a DT strategy: ``regress --weights NAME=FILE``, ``demo`` and ``teach --weights FILE``.

The file is the one ``teachbot learn-weights`` writes (``learning.decision.weights_file``): the features it
names are the decision features the strategy uses, any left out weigh 0. What travels to worker
processes, Ray tasks and transcript headers is the file's path and its values, never an open object.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from learning.decision.habits import EXTENDED_FEATURE_NAMES
from learning.decision.weights import PRESETS, weight_vector
from learning.decision.weights_file import load_weights
from learning.errors import DataFileError, SettingsError, TranscriptError
from learning.strategies import STRATEGY_NAMES, DecisionTheoreticStrategy

DT_STRATEGIES = PRESETS  # the strategies --weights may stand in for: all of them are DT with some weights
WEIGHTS_STRATEGY_NAME = "dt"  # what demo and teach show (and record) for DT with the user's weights


@dataclass(frozen=True)
class UserWeights:
    """The weights of a user's file: its path and its values ((feature, weight), ...) in the file's order."""

    file: str
    values: tuple[tuple[str, float], ...]

    def strategy(self, name: str = WEIGHTS_STRATEGY_NAME) -> DecisionTheoreticStrategy:
        """DT with these weights, reported as ``name``."""
        return DecisionTheoreticStrategy(weights=dict(self.values), name=name)

    def record(self) -> dict:
        """What a transcript header or a report stores: the file and the values."""
        return {"file": self.file, "values": dict(self.values)}

    def never_asks(self) -> bool:
        """True when no state can make a question score above staying quiet: every weight is 0 but perhaps
        remaining_time's, which under eq. 7.1 is the same for every candidate of a turn (ties go to no query)."""
        return all(value == 0 for name, value in self.values if name != "remaining_time")

    def warn_if_never_asks(self) -> None:
        """One line on stderr when :meth:`never_asks`: such a file runs, but the robot stays quiet every turn."""
        if self.never_asks():
            print(f"warning: {self.file}: every weight that can tell a question from staying quiet is 0, so this DT "
                  "never asks (every turn ties with no query); fit the weights again (teachbot learn-weights) or edit "
                  "the file", file=sys.stderr, flush=True)

    def describe(self) -> str:
        return f"{self.file} (" + ", ".join(f"{name} {value:g}" for name, value in self.values) + ")"


def read_user_weights(path: str | Path) -> UserWeights:
    """The weights in ``path``; a missing or malformed file, or an unknown feature, is one DataFileError."""
    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"{path}: no weights file there (write one with teachbot learn-weights, or by hand: "
                            "a [weights] table of decision feature = number)")
    loaded = load_weights(path)
    try:
        weight_vector(loaded.as_dict(), str(path))  # every name a decision feature
    except ValueError as error:
        raise DataFileError(str(error)) from None
    return UserWeights(str(path.resolve()), tuple(loaded.as_dict().items()))  # absolute: resumable from anywhere


def named_weights(text: str) -> tuple[str, Path]:
    """An argparse type for ``NAME=FILE``: a new strategy name and the weights file it runs with."""
    name, equals, file = text.partition("=")
    name = name.strip()
    if not equals or not name or not file:
        raise argparse.ArgumentTypeError(f"expected NAME=FILE (a new strategy name and a weights .toml file), "
                                         f"got '{text}'")
    if name.lower() in STRATEGY_NAMES:
        raise argparse.ArgumentTypeError(f"'{name}' is a built-in strategy; choose a name that is not one of "
                                         f"{', '.join(STRATEGY_NAMES)}")
    if not all(c.isascii() and (c.isalnum() or c in "-_.") for c in name):
        raise argparse.ArgumentTypeError(f"strategy name '{name}' is not accepted; use letters, digits, '-', '_' "
                                         "or '.' (it names files in the results folder)")
    return name, Path(file)


def read_named_weights(pairs) -> dict[str, UserWeights]:
    """``{NAME: UserWeights}`` from ``--weights NAME=FILE`` pairs; a name given twice is refused."""
    found: dict[str, UserWeights] = {}
    for name, path in pairs or ():
        if name in found:
            raise SettingsError(f"--weights: the strategy name '{name}' is given twice; give each its own name")
        found[name] = read_user_weights(path)
        found[name].warn_if_never_asks()
    return found


def weights_strategy(strategy: str, weights_file: Path | None) -> tuple[str, UserWeights | None]:
    """The strategy name to show and the user's weights for ``--strategy`` beside ``--weights`` (None: none given).

    With ``--weights`` the strategy is DT with those weights, shown as ``dt``; a non-DT ``--strategy`` is refused.
    """
    if weights_file is None:
        return strategy, None
    if strategy not in DT_STRATEGIES:
        raise SettingsError(f"--weights gives the weights of a decision-theoretic strategy, but --strategy {strategy} "
                            f"does not use weights; leave --strategy out or give one of {', '.join(DT_STRATEGIES)}")
    weights = read_user_weights(weights_file)
    weights.warn_if_never_asks()
    return WEIGHTS_STRATEGY_NAME, weights


def weights_from_record(recorded) -> UserWeights:
    """The weights a record holds (``{"file": path, "values": {feature: weight}}``), or SettingsError."""
    values = recorded.get("values") if isinstance(recorded, dict) else None
    file = recorded.get("file") if isinstance(recorded, dict) else None
    good = isinstance(values, dict) and values and isinstance(file, str) and file and all(
        name in EXTENDED_FEATURE_NAMES and isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
        for name, v in values.items())
    if not good:
        raise SettingsError("weights must be a table with the weights file and its values, one finite number per "
                            f"decision feature of {', '.join(EXTENDED_FEATURE_NAMES)}; got {recorded!r:.120}")
    return UserWeights(file, tuple((name, float(v)) for name, v in values.items()))


def weights_from_header(recorded, path) -> UserWeights | None:
    """The weights a transcript header records (None: the session used a built-in strategy)."""
    if recorded is None:
        return None
    try:
        return weights_from_record(recorded)
    except SettingsError as error:
        raise TranscriptError(f"{path}: line 1: the session header's 'weights' is not accepted ({error})") from None


def check_weights_unchanged(recorded: UserWeights, path) -> None:
    """A resumed session goes on with the weights it recorded: the file must still hold the same values."""
    try:
        now = read_user_weights(recorded.file)
    except DataFileError as error:
        raise TranscriptError(f"{path}: the session was recorded with the weights in {recorded.file}, which can't "
                              f"be read now ({error}); restore that file to resume") from None
    if dict(now.values) != dict(recorded.values):
        raise TranscriptError(f"{path}: the weights file {recorded.file} changed since the session was recorded "
                              f"(recorded {dict(recorded.values)}, now {dict(now.values)}); restore it, or start a "
                              "new session without --resume")


def add_weights_option(parser: argparse.ArgumentParser) -> None:
    """``--weights FILE`` of demo and teach: DT with the weights in FILE, shown and recorded as ``dt``."""
    parser.add_argument("--weights", type=Path, default=None, metavar="FILE",
                        help="run DT with the weights in FILE (a weights .toml as teachbot learn-weights writes it); "
                             f"the strategy is shown as '{WEIGHTS_STRATEGY_NAME}' and the transcript header records "
                             "the file and its values; --strategy, if given, must be a DT one")
