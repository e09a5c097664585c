"""Pure learning: concept models, query strategies, evaluation.

Imports nothing from the simulator, viewer or OpenCV: every function here works
on plain feature matrices, so the strategies run on any data set.

The public API (docs/library.md) is loaded on first use, so that importing a
submodule such as ``learning.gp`` does not pull in scikit-learn:

- ``ConceptClassifier``: a scikit-learn classifier of one binary GP per class;
- ``TeachingLoop``: observe a scene, ``ask`` a ``Query``, ``tell`` the answer;
- ``LearningState.apply`` (also ``apply_answer``): the one place an answer changes the learner;
- ``Strategy``, ``Decision`` and the actions (``LabelQuery``, ``DemoQuery``, ``FeatureQuery``, ``NoQuery``):
  a strategy of your own, which ``check_strategy`` checks and ``module.path:ClassName`` runs.
"""

from importlib import import_module

_EXPORTS = {
    "ConceptClassifier": "learning.classifier",
    "TeachingLoop": "learning.loop",
    "Query": "learning.loop",
    "Turn": "learning.loop",
    "CallOrderError": "learning.loop",
    "admissible": "learning.turn",
    "apply_answer": "learning.answers",
    "check_answer": "learning.answers",
    "Change": "learning.answers",
    "DemoRow": "learning.answers",
    "AnswerError": "learning.answers",
    "LearningState": "learning.state",
    "STRATEGY_NAMES": "learning.strategies",
    "make_strategy": "learning.strategies",
    "Strategy": "learning.strategies.base",
    "check_strategy": "learning.strategies.check",
    "StrategyCheckError": "learning.strategies.check",
    "Decision": "learning.actions",
    "Action": "learning.actions",
    "LabelQuery": "learning.actions",
    "DemoQuery": "learning.actions",
    "FeatureQuery": "learning.actions",
    "NoQuery": "learning.actions",
    "TeachbotError": "learning.errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'learning' has no attribute {name!r}")
    value = getattr(import_module(_EXPORTS[name]), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
