"""A user's own strategy, ``module.path:ClassName``: imported from an importable module (this runs the user's code).

The module is found on ``sys.path`` (put its folder on ``PYTHONPATH``) by its
dotted name; nothing is loaded from a file path or by pickle. The class must be
a subclass of :class:`learning.Strategy`, or have a callable
``choose(state, rng)``; it is built with no arguments (or the options given to
``make_strategy``). An instance without a ``name`` of its own is named by the
spec, so reports label it ``module.path:ClassName``.
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any

from learning.errors import SettingsError
from learning.strategies.rl_questioner import PREFIX as RL_PREFIX

SEPARATOR = ":"
FORM = "module.path:ClassName (your own Strategy class in an importable module)"


def is_plugin_spec(name) -> bool:
    """True for names of the form ``something:Something`` that are not ``rl:FILE`` (a trained policy)."""
    text = str(name)
    return SEPARATOR in text and not text.startswith(RL_PREFIX)


def split_spec(spec: str) -> tuple[str, str]:
    """``(module path, class name)`` of ``spec``, or one SettingsError saying what is accepted."""
    module, _, cls = str(spec).strip().partition(SEPARATOR)
    if "/" in module or "\\" in module or module.endswith(".py"):
        raise SettingsError(f"strategy '{spec}': a strategy is loaded from an importable module, not a file path; "
                            f"put the file's folder on PYTHONPATH and give its dotted name, as {FORM}")
    dotted = module.split(".")
    if not module or not all(part.isidentifier() for part in dotted) or not cls.isidentifier():
        raise SettingsError(f"strategy '{spec}' is not of the form {FORM}: a dotted module name, a colon, then a "
                            f"class name")
    return module, cls


def load_plugin(spec: str, **options) -> Any:
    """An instance of the class ``spec`` names (the user's code runs here); SettingsError says what went wrong."""
    module_name, cls_name = split_spec(spec)
    try:
        module = importlib.import_module(module_name)
    except Exception as error:  # the user's module: any error it raises on import is theirs to see in one line
        raise SettingsError(f"strategy '{spec}': can't import module '{module_name}' ({type(error).__name__}: "
                            f"{error}); it must be importable (on PYTHONPATH), as {FORM}") from None
    cls = getattr(module, cls_name, None)
    if cls is None:
        raise SettingsError(f"strategy '{spec}': module '{module_name}' has no '{cls_name}'; expected {FORM}")
    if not inspect.isclass(cls) or not callable(getattr(cls, "choose", None)):
        raise SettingsError(f"strategy '{spec}': '{cls_name}' is not a strategy class (a subclass of "
                            f"learning.Strategy, or a class with a choose(state, rng) method)")
    try:
        strategy: Any = cls(**options)
    except Exception as error:  # a constructor that fails is the user's error, shown in one line
        raise SettingsError(f"strategy '{spec}': {cls_name}({', '.join(f'{k}=...' for k in sorted(options))}) "
                            f"failed ({type(error).__name__}: {error}); it must build with no arguments") from None
    if not getattr(strategy, "name", ""):
        try:
            strategy.name = str(spec).strip()
        except AttributeError:  # a read-only name: reports use the spec anyway
            pass
    _check_once(strategy, spec)
    return strategy


#: plug-in classes loaded in this process, each checked once by ``learning.check_strategy``
_PLUGIN_CLASSES: set[type] = set()


def _check_once(strategy, spec: str) -> None:
    """Refuse a plug-in that breaks the strategy contract before it plays (checked once per class)."""
    from learning.strategies.check import StrategyCheckError, check_strategy

    if type(strategy) in _PLUGIN_CLASSES:
        return
    try:
        check_strategy(strategy)
    except StrategyCheckError as error:
        broken = str(error).removeprefix(f"{getattr(strategy, 'name', '')} ")
        raise StrategyCheckError(f"strategy '{spec}' is refused (learning.check_strategy): a strategy {broken}") \
            from None
    _PLUGIN_CLASSES.add(type(strategy))


def is_plugin(strategy) -> bool:
    """True for a strategy built from ``module.path:ClassName`` (the user's code, held to the contract)."""
    return type(strategy) in _PLUGIN_CLASSES


def plugin_file_label(spec: str) -> str:
    """``pkg.mod:Class`` as a file name: ``pkg.mod.Class`` (no ':', which some file systems refuse)."""
    module, _, cls = str(spec).strip().partition(SEPARATOR)
    return f"{module}.{cls}"
