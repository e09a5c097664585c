"""The commands teachbot prints for a person to run (resume, continue, report): runnable as printed (issue 51).

A "continue it with: teachbot teach --resume t.jsonl" line fails with "teachbot: command not found" when the
person ran ``.venv/bin/teachbot`` without activating the virtual environment. So every such line names the
program the way it was started: ``teachbot`` when that name on PATH is this very program, otherwise the path
the person typed (relative when they typed it relative, so it still works from the folder it was printed in).
The words are quoted for a POSIX shell; the paths in them are the ones the person gave, relative to the same
folder. Run in another way (a library user, a test, ``python -m dialog.cli``), the lines say ``teachbot``, the
installed name.
"""

from __future__ import annotations

import os
import shlex
import shutil
import sys
from collections.abc import Iterable

NAME = "teachbot"  # the console script pyproject.toml installs


def program(argv0: str | None = None) -> list[str]:
    """The words that start this program again from the current folder (``argv0``: default ``sys.argv[0]``)."""
    argv0 = sys.argv[0] if argv0 is None else argv0
    if os.path.basename(argv0) != NAME:  # not started as the teachbot program
        return [NAME]
    found = shutil.which(NAME)
    if found is not None and _same_file(found, argv0):
        return [NAME]
    return [argv0 if os.sep in argv0 else os.path.join(os.curdir, argv0)]  # "teachbot" in this folder: ./teachbot


def command_line(words: Iterable) -> str:
    """``teachbot WORDS...`` as a person can paste it: the program as it was started (:func:`program`) and
    ``words`` (the command and its arguments, str() of each), quoted for a POSIX shell."""
    return shlex.join(program() + [str(word) for word in words])


def _same_file(a: str, b: str) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False
