"""Decision-feature weights w of U(s) = w . phi(s) as a TOML data file (thesis eq. 7.2).

This is the file the DT-task-env preset reads. Format::

    # written by teachbot: maximum-entropy IRL weights (thesis eq. 7.5-7.7)
    [weights]                       # required: one finite number per decision feature, in feature order
    classifier_discriminability = 0.84
    budget_consumption = -2.1
    ...

    [provenance]                    # optional: how the weights were made (strings, numbers, booleans)
    method = "maxent-irl"
    iterations = 41
    validation_agreement = 0.93

Only the order and values of ``[weights]`` matter to a strategy; a reader that
passes the feature names it expects gets a clear error for a missing or an
unknown name. Feature names are TOML bare keys (letters, digits, ``_``, ``-``).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learning.datafiles import read_toml
from learning.decision.features import check_feature_names
from learning.errors import DataFileError
from learning.limits import check_limit

WEIGHTS_TABLE = "weights"
PROVENANCE_TABLE = "provenance"


@dataclass(frozen=True, eq=False)
class DecisionWeights:
    """Named weights of the decision features (thesis eq. 7.2) and where they came from."""

    feature_names: tuple[str, ...]
    values: np.ndarray
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        names = check_feature_names(self.feature_names, "weights")
        values = np.array(self.values, dtype=np.float64)
        if values.shape != (len(names),):
            raise ValueError(f"weights: expected {len(names)} values (one per feature), got shape {values.shape}")
        if not np.all(np.isfinite(values)):
            raise ValueError("weights: every weight must be a finite number")
        if values.size:
            check_limit("weight", float(np.max(np.abs(values))), "weights: the largest weight (its size)")
        values.setflags(write=False)
        object.__setattr__(self, "feature_names", names)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "provenance", _check_provenance(self.provenance, "weights provenance"))

    def as_dict(self) -> dict[str, float]:
        return {name: float(value) for name, value in zip(self.feature_names, self.values)}

    def vector(self, feature_names: Sequence[str]) -> np.ndarray:
        """The weights in the caller's feature order; every name must be known and none left over."""
        _check_same_names(self.feature_names, feature_names, "weights")
        lookup = self.as_dict()
        return np.array([lookup[name] for name in feature_names], dtype=np.float64)


def _check_same_names(have: Sequence[str], expected: Sequence[str], source: str) -> None:
    missing = [name for name in expected if name not in have]
    unknown = [name for name in have if name not in expected]
    if missing or unknown:
        raise ValueError(f"{source}: weights must name exactly the features {', '.join(expected)}; "
                         f"missing {missing}, unknown {unknown}")


def _check_provenance(provenance, source: str) -> dict:
    if not isinstance(provenance, Mapping):
        raise ValueError(f"{source}: expected a table, got {type(provenance).__name__}")
    for key, value in provenance.items():
        if not isinstance(key, str) or not check_bare_key(key):
            raise ValueError(f"{source}: key {key!r} is not accepted; use letters, digits, '_' or '-'")
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{source}: {key} must be finite, got {value}")
        if not isinstance(value, str | int | float | bool):
            raise ValueError(f"{source}: {key} must be a string, number or boolean, got {type(value).__name__}")
    return dict(provenance)


def check_bare_key(key: str) -> bool:
    return bool(key) and all(c.isascii() and (c.isalnum() or c in "_-") for c in key)


def toml_value(value) -> str:
    """One TOML value (boolean, integer, float, string, or a list of these) as text."""
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return repr(float(value))  # shortest round-trip form: '0.25', '-1.5e-07' (both valid TOML floats)
    # a TOML basic string: JSON's escapes are TOML's, except DEL, which TOML wants escaped too
    return json.dumps(str(value), ensure_ascii=False).replace("\x7f", "\\u007f")


def weights_to_toml(weights: DecisionWeights, comment: str = "") -> str:
    """The TOML text of a weights file (written by hand: two flat tables)."""
    lines = [f"# {line}".rstrip() for line in comment.splitlines()] if comment else []
    lines += [f"[{WEIGHTS_TABLE}]"]
    lines += [f"{name} = {toml_value(float(value))}" for name, value in zip(weights.feature_names, weights.values)]
    if weights.provenance:
        lines += ["", f"[{PROVENANCE_TABLE}]"]
        lines += [f"{key} = {toml_value(value)}" for key, value in weights.provenance.items()]
    return "\n".join(lines) + "\n"


def save_weights(path: str | Path, weights: DecisionWeights, comment: str = "") -> Path:
    """Write the weights file; ``comment`` lines go at the top as TOML comments."""
    path = Path(path)
    if path.suffix != ".toml":
        raise ValueError(f"{path}: a weights file must end in .toml")
    # written beside the target and renamed over it: a failed write (a full disk) never leaves half a file
    partial = path.with_name(f".{path.name}.partial")
    try:
        partial.write_text(weights_to_toml(weights, comment), encoding="utf-8")
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    return path


def load_weights(path: str | Path, feature_names: Sequence[str] | None = None) -> DecisionWeights:
    """Read a weights TOML file; with ``feature_names`` the weights come back in that order, all present."""
    return weights_from_mapping(read_toml(path, "weights"), feature_names, source=str(path))


def weights_from_mapping(data: Mapping, feature_names: Sequence[str] | None = None,
                         source: str = "weights") -> DecisionWeights:
    """Validate parsed TOML (``[weights]`` and optional ``[provenance]``) into DecisionWeights."""
    unknown = sorted(set(data) - {WEIGHTS_TABLE, PROVENANCE_TABLE})
    if unknown:
        raise DataFileError(f"{source}: unknown table or key {unknown[0]!r}; accepted: [{WEIGHTS_TABLE}], "
                         f"[{PROVENANCE_TABLE}]")
    table = data.get(WEIGHTS_TABLE)
    if not isinstance(table, Mapping) or not table:
        raise DataFileError(f"{source}: needs a non-empty [{WEIGHTS_TABLE}] table of feature = number")
    for name, value in table.items():
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise DataFileError(f"{source}: weight {name!r} must be a finite number, got {value!r}")
        check_limit("weight", abs(value), f"{source}: weight {name!r} (its size)", DataFileError)
    try:
        names = check_feature_names(list(table), f"{source} [{WEIGHTS_TABLE}]")
        if feature_names is not None:
            _check_same_names(names, check_feature_names(feature_names, "expected features"), source)
            names = tuple(feature_names)
        provenance = _check_provenance(data.get(PROVENANCE_TABLE, {}), f"{source} [{PROVENANCE_TABLE}]")
    except ValueError as error:
        message = str(error)
        raise DataFileError(message if message.startswith(source) else f"{source}: {message}") from None
    return DecisionWeights(names, np.array([float(table[name]) for name in names]), provenance)
