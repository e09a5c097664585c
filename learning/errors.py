"""The one base class for errors that reach a user as a single message, never a traceback.

The command line catches :class:`TeachbotError` (and, for now, the ``ValueError``
family it derives from) and prints ``teachbot COMMAND: message``. A message names
what was wrong (the file, line, field, path or answer) and what is accepted.
Anything else is a bug and keeps its traceback.
"""

from __future__ import annotations


class TeachbotError(ValueError):
    """Bad input of any kind: a file, a path, a value, a recorded session."""


class DataFileError(TeachbotError):
    """A data file (kitchen, task, objects, features, recipe, suite, weights, vocabulary) is missing or invalid."""


class OutputPathError(TeachbotError):
    """A path the tool must write cannot be written (full disk, read-only, a folder, a file as parent, no access)."""


class TranscriptError(TeachbotError):
    """A transcript cannot be resumed or is held by another process."""
