"""Weight vectors w of U(s) = w . phi(s) (thesis eq. 6.2, 7.2), read from TOML files in learning/decision/presets/.

File format (the one the IRL tools write)::

    [weights]                           # feature name = number; a feature left out weighs 0
    classifier_discriminability = 1.0
    class_distribution_uniformity = 0.5

    [provenance]                        # optional: strings, numbers or booleans about where they came from
    method = "hand-set"

Names are those of ``learning.decision.features.FEATURE_NAMES`` (the thesis's seven) and, for a feature set
that weighs the expert's habits too, ``learning.decision.habits.HABIT_FEATURES``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from learning.decision.features import FEATURE_NAMES
from learning.decision.habits import EXTENDED_FEATURE_NAMES, HABIT_FEATURES
from learning.decision.weights_file import load_weights
from learning.errors import SettingsError, did_you_mean
from learning.limits import check_limit

WEIGHTS_DIRECTORY = Path(__file__).resolve().parent / "presets"
# dt-task-env weighs the thesis's seven features with the thesis's signs (issue 39); dt-task-env-v1 the seven and
# the expert-habit features (issue 27); dt-task-env-thesis the seven by the earlier trajectory fit; the last two
# are issue 27's pre-registered ablations of dt-task-env-v1
# (docs/irl.md); dt-iros-v1 and dt-task-v1 keep the hand-set weights of dt-iros and dt-task from before issue 39's
# calibration rule (docs/calibration.md).
PRESETS = ("dt", "dt-iros", "dt-task", "dt-iros-v1", "dt-task-v1",
           "dt-task-env", "dt-task-env-v1", "dt-task-env-thesis", "dt-task-env-no-env", "dt-task-habits")


def weight_vector(weights: Mapping[str, float] | Sequence[float] | np.ndarray, source: str = "weights") -> np.ndarray:
    """w from a {name: weight} mapping (missing names weigh 0) or a full sequence: in FEATURE_NAMES order, or in
    EXTENDED_FEATURE_NAMES order when the mapping names a habit feature (or the sequence has one weight each)."""
    if isinstance(weights, Mapping):
        unknown = sorted(set(weights) - set(EXTENDED_FEATURE_NAMES))
        if unknown:
            raise ValueError(f"{source}: unknown decision feature {unknown[0]!r}; accepted: "
                             f"{', '.join(EXTENDED_FEATURE_NAMES)}")
        names = EXTENDED_FEATURE_NAMES if set(weights) & set(HABIT_FEATURES) else FEATURE_NAMES
        values = [weights.get(name, 0.0) for name in names]
    else:
        values = list(weights)
        names = EXTENDED_FEATURE_NAMES if len(values) == len(EXTENDED_FEATURE_NAMES) else FEATURE_NAMES
        if len(values) != len(names):
            raise ValueError(f"{source}: expected {len(FEATURE_NAMES)} weights in the order "
                             f"{', '.join(FEATURE_NAMES)} (or {len(EXTENDED_FEATURE_NAMES)} with "
                             f"{', '.join(HABIT_FEATURES)} after them); got {len(values)}")
    for name, value in zip(names, values):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                or not math.isfinite(value):
            raise ValueError(f"{source}: weight of {name} must be a finite real number, got {value!r}")
        check_limit("weight", abs(value), f"{source}: weight of {name} (its size)")
    return np.array(values, dtype=float)


def weighs_habits(weights: np.ndarray) -> bool:
    """True for a vector over EXTENDED_FEATURE_NAMES (its candidates need the habit columns)."""
    return len(weights) == len(EXTENDED_FEATURE_NAMES)


def load_weight_file(path: str | Path) -> np.ndarray:
    """w from a weights TOML file (read by ``learning.decision.weights_file``, the one reader of the format); a bad file
    gets a one-line message naming the file and what is accepted."""
    return weight_vector(load_weights(path).as_dict(), str(path))


def preset_weights(name: str) -> np.ndarray:
    """The weights of a named preset (``PRESETS``), from learning/decision/presets/<name>.toml."""
    if name not in PRESETS:
        raise SettingsError(f"unknown weight preset '{name}'{did_you_mean(name, PRESETS)}; choose one of: "
                            f"{', '.join(PRESETS)}")
    return load_weight_file(WEIGHTS_DIRECTORY / f"{name}.toml")


def resolve_weights(weights) -> np.ndarray:
    """Accept a preset name, a path to a TOML file, a {feature: weight} mapping or a full vector."""
    if isinstance(weights, str) and weights in PRESETS:
        return preset_weights(weights)
    if isinstance(weights, (str, Path)):
        return load_weight_file(weights)
    return weight_vector(weights)
