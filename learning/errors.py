"""The one base class for errors that reach a user as a single message, never a traceback.

The command line catches :class:`TeachbotError` (and nothing else) and prints
``teachbot COMMAND: message``; it stays a ``ValueError`` so that library users who
catch ``ValueError`` still catch it. A message names
what was wrong (the file, line, field, path or answer) and what is accepted.
Anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import difflib


class TeachbotError(ValueError):
    """Bad input of any kind: a file, a path, a value, a recorded session."""


class DataFileError(TeachbotError):
    """A data file (kitchen, task, objects, features, recipe, suite, weights, vocabulary) is missing or invalid."""


class OutputPathError(TeachbotError):
    """A path the tool must write cannot be written (full disk, read-only, a folder, a file as parent, no access)."""


class TranscriptError(TeachbotError):
    """A transcript cannot be resumed or is held by another process."""


class SettingsError(TeachbotError):
    """A setting (a command-line option, an episode or teacher setting, a suite option) has a value not accepted."""


class SceneError(TeachbotError, RuntimeError):
    """The kitchen, task or recipe cannot hold what was asked of it (objects that do not fit, a missing location).

    Also a ``RuntimeError``, which placement failures were before.
    """


class SetupError(TeachbotError, RuntimeError):
    """An optional extra or a facility the command needs (Ray, Chromium, the viewer server) is missing or failed.

    Also a ``RuntimeError``, which these were before.
    """


class MessageError(TeachbotError):
    """A message from the browser page (``--web``) is malformed, forged or stale; it is refused and changes
    nothing."""


def did_you_mean(text: str, names) -> str:
    """" (did you mean 'dt-task'?)" when ``text`` is close to one of ``names`` (the closest), else "": the hint
    an unknown name's message carries."""
    close = difflib.get_close_matches(str(text).lower(), [str(n) for n in names], n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""
