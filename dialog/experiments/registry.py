"""The registry of suite kinds, by name: filled by ``register_kind``, the built-in kinds loaded when first asked for.

It imports no suite module at all, not even for its types: the suite file reader (``dialog.experiments.suite``)
checks a suite's ``kind`` against it, and the kinds (``dialog.experiments.kinds``, which imports that reader)
register here, so a name of theirs here would close a circle. The registry holds any class with a ``name``;
``dialog.experiments.kinds.get_kind`` checks that what it hands out is a ``SuiteKind``.
"""

from __future__ import annotations

import importlib
from typing import Any, TypeVar

BUILTIN_KIND_MODULES = ("dialog.experiments.episode_kind", "dialog.experiments.features.kind",
                        "dialog.experiments.recipes.kind")

Kind = TypeVar("Kind", bound=type)
_KINDS: dict[str, Any] = {}  # name -> an instance of the registered kind, built-in ones first


def register_kind(kind: Kind) -> Kind:
    """Register a ``SuiteKind`` subclass under its ``name`` (usable as a class decorator)."""
    name = getattr(kind, "name", "")
    if not isinstance(name, str) or not name:
        raise TypeError(f"{kind.__name__} needs a non-empty class attribute 'name'")
    if name in _KINDS and type(_KINDS[name]) is not kind:
        raise ValueError(f"a suite kind named '{name}' is already registered ({type(_KINDS[name]).__name__})")
    _KINDS[name] = kind()
    return kind


def _load_builtin_kinds() -> None:
    for module in BUILTIN_KIND_MODULES:
        importlib.import_module(module)


def kind_names() -> tuple[str, ...]:
    """The registered kinds, built-in ones first."""
    _load_builtin_kinds()
    return tuple(_KINDS)


def registered() -> dict[str, Any]:
    """The registered kinds by name (the built-in ones loaded first)."""
    _load_builtin_kinds()
    return _KINDS
