"""The one way a command writes JSON (``--json`` lines, ``learn-weights --report``): strict JSON, never ``NaN`` or
``Infinity``, which JSON has no words for; a number that is not finite is ``null``."""

from __future__ import annotations

import json
import math
import sys


def finite(value):
    """``value`` with every float that is not finite (NaN, +-inf) replaced by None, tuples as lists."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: finite(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(item) for item in value]
    return value


def strict_json(value, **options) -> str:
    """``json.dumps`` of ``value`` as strict JSON (``allow_nan=False`` after :func:`finite`)."""
    return json.dumps(finite(value), allow_nan=False, **options)


def print_json(value, file=None) -> None:
    """Print ``value`` as one line of strict JSON."""
    print(strict_json(value), file=file or sys.stdout, flush=True)
