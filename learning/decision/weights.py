"""Weight vectors w of U(s) = w . phi(s) (thesis eq. 6.2, 7.2), read from TOML files in learning/decision/presets/.

File format (the one the IRL tools write)::

    [weights]                           # feature name = number; a feature left out weighs 0
    classifier_discriminability = 1.0
    class_distribution_uniformity = 0.5

    [provenance]                        # optional: strings, numbers or booleans about where they came from
    method = "hand-set"

Names are those of ``learning.decision.features.FEATURE_NAMES``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from learning.decision.features import FEATURE_NAMES
from learning.decision.weights_file import load_weights
from learning.errors import SettingsError, did_you_mean
from learning.limits import check_limit

WEIGHTS_DIRECTORY = Path(__file__).resolve().parent / "presets"
PRESETS = ("dt", "dt-iros", "dt-task", "dt-task-env")


def weight_vector(weights: Mapping[str, float] | Sequence[float] | np.ndarray, source: str = "weights") -> np.ndarray:
    """w in FEATURE_NAMES order from a {name: weight} mapping (missing names weigh 0) or a full sequence."""
    if isinstance(weights, Mapping):
        unknown = sorted(set(weights) - set(FEATURE_NAMES))
        if unknown:
            raise ValueError(f"{source}: unknown decision feature {unknown[0]!r}; accepted: {', '.join(FEATURE_NAMES)}")
        values = [weights.get(name, 0.0) for name in FEATURE_NAMES]
    else:
        values = list(weights)
        if len(values) != len(FEATURE_NAMES):
            raise ValueError(f"{source}: expected {len(FEATURE_NAMES)} weights in the order "
                             f"{', '.join(FEATURE_NAMES)}; got {len(values)}")
    for name, value in zip(FEATURE_NAMES, values):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                or not math.isfinite(value):
            raise ValueError(f"{source}: weight of {name} must be a finite real number, got {value!r}")
        check_limit("weight", abs(value), f"{source}: weight of {name} (its size)")
    return np.array(values, dtype=float)


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
