"""The one validation layer for teachbot's TOML data files (kitchen, task, objects, features, recipe, suite,
weights, vocabulary, colour table, expert rules).

:func:`read_toml` reads a file (refusing binary and non-UTF-8 files); the field checkers take the parsed
table, a key and ``where`` (the file and section, e.g. ``"kitchen.toml [camera]"``) and either return a
clean value or raise :class:`DataFileError` with one line naming the file, the field and what is accepted.
Numbers must be finite (TOML allows ``nan`` and ``inf``); ``[low, high]`` ranges need low <= high; unknown
keys list the accepted ones and suggest the nearest ("did you mean").
"""

from __future__ import annotations

import difflib
import errno
import math
import os
import re
import sys
from collections.abc import Iterable
from pathlib import Path

from learning.errors import DataFileError

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10
    import tomli as tomllib

__all__ = ["NAME_RULE", "REQUIRED", "DataFileError", "MissingDataFileError", "check_keys", "check_name", "flag",
           "integer", "inside", "name", "number", "numbers", "read_toml", "section", "tables", "text", "texts",
           "value_range"]

#: the one pattern for every name that becomes part of a path (suite, study, condition, participant)
NAME_PATTERN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9._-]{0,63}")
NAME_RULE = ("1 to 64 letters, digits, '-', '_' or '.', starting with a letter, digit or '_' "
             "(no spaces, path separators or newlines)")


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = _Required()  # the default of a field that must be present


class MissingDataFileError(DataFileError, FileNotFoundError):
    """A data file does not exist (still a ValueError for the command line, and a FileNotFoundError)."""


def lookup_problem(path: str | Path) -> str:
    """Why ``path`` can't even be looked up ("" when it can, or when it is just missing): a name longer than the
    file system allows, a path longer than the system allows, or symbolic links that loop."""
    text = os.fspath(path)
    try:
        os.stat(text)
    except (FileNotFoundError, NotADirectoryError, PermissionError):
        return ""  # the callers say these in their own words
    except OSError as error:
        if error.errno == errno.ENAMETOOLONG:
            longest = max((len(part.encode("utf-8", "surrogateescape")) for part in Path(text).parts), default=0)
            limit = _limit(text, "PC_NAME_MAX", 255)
            if longest > limit:
                return f"a name in the path is {longest} bytes long; this file system allows at most {limit} " \
                       "(ENAMETOOLONG)"
            return (f"the path is {len(text.encode('utf-8', 'surrogateescape')):,} bytes long; this system allows "
                    f"at most {_limit('/', 'PC_PATH_MAX', 4096) - 1:,} (ENAMETOOLONG)")
        if error.errno == errno.ELOOP:
            return "symbolic links in the path loop (or nest too deeply) (ELOOP)"
        raise
    return ""


def _limit(text: str, name: str, default: int) -> int:
    folder = os.path.dirname(text) or "."
    while folder and not os.path.isdir(folder) and folder != os.path.dirname(folder):
        folder = os.path.dirname(folder) or "."
    try:
        return os.pathconf(folder if os.path.isdir(folder) else "/", name)
    except (OSError, ValueError):
        return default


def read_toml(path: str | Path, what: str = "data") -> dict:
    """The parsed TOML file; one-line DataFileError when it is missing, a folder, binary, not UTF-8 or not TOML."""
    path = Path(path)
    problem = lookup_problem(path)
    if problem:
        raise DataFileError(f"{what} file {str(path)[:160]}: cannot be read: {problem}")
    if not path.exists():
        raise MissingDataFileError(f"{what} file {path} does not exist")
    if not path.is_file():
        raise DataFileError(f"{what} file {path} is not a file; give the path of a .toml file")
    raw = path.read_bytes()
    if b"\x00" in raw:
        raise DataFileError(f"{path}: is a binary file, not a TOML {what} file")
    try:
        content = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        raise DataFileError(f"{path}: is not UTF-8 text (byte {error.start}); a {what} file must be UTF-8 TOML") \
            from None
    try:
        return tomllib.loads(content)
    except tomllib.TOMLDecodeError as error:
        raise DataFileError(f"{path}: not valid TOML ({error})") from None
    except RecursionError:
        raise DataFileError(f"{path}: not valid TOML for teachbot: arrays or tables nested too deeply "
                            "(a data file needs a few levels at most)") from None


def check_name(value, what: str, where: str) -> str:
    """A name that becomes part of a path: a full match of :data:`NAME_PATTERN`, else one line saying the rule."""
    if not isinstance(value, str) or NAME_PATTERN.fullmatch(value) is None:
        shown = repr(value) if len(repr(value)) <= 80 else f"{repr(value)[:80]}... ({len(value)} characters)"
        raise DataFileError(f"{where}: {what} {shown} is not accepted; a name is {NAME_RULE}")
    return value


def name(table: dict, key: str, where: str, default=REQUIRED, what: str | None = None) -> str:
    """A field whose value names a file or folder (:func:`check_name`)."""
    present, value = _present(table, key, where, default)
    return check_name(value, what or f"'{key}'", where) if present else value


def inside(folder: str | Path, path: str | Path, what: str) -> Path:
    """``path`` if it stays inside ``folder`` once symbolic links are followed, else one line naming both."""
    base, full = os.path.realpath(folder), os.path.realpath(path)
    if os.path.commonpath([base, full]) != base:
        raise DataFileError(f"{path}: the {what} would be written outside its folder {folder} (it resolves to "
                            f"{full}); a symbolic link may point out of it")
    return Path(path)


def check_keys(table: dict, where: str, required: Iterable[str] = (), optional: Iterable[str] = ()) -> None:
    """Refuse a missing required key and any key not accepted (a typo gets "did you mean")."""
    required, optional = tuple(required), tuple(optional)
    if not isinstance(table, dict):
        raise DataFileError(f"{where}: must be a table, got {_show(table)}")
    accepted = tuple(dict.fromkeys(required + optional))  # each once, in order
    for key in table:
        if key not in accepted:
            close = difflib.get_close_matches(str(key), accepted, n=1, cutoff=0.6)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise DataFileError(f"{where}: unknown field '{key}'; accepted fields: {', '.join(accepted) or 'none'}"
                                f"{hint}")
    missing = [key for key in required if key not in table]
    if missing:
        raise DataFileError(f"{where}: missing field '{missing[0]}' (required: {', '.join(required)})")


def _show(value) -> str:
    return f"{type(value).__name__} {value!r}" if not isinstance(value, (int, float, str)) else repr(value)


def _present(table: dict, key: str, where: str, default):
    """(True, value) when ``key`` is in the table, (False, default) when it may be left out."""
    if key in table:
        return True, table[key]
    if default is REQUIRED:
        raise DataFileError(f"{where}: missing field '{key}'")
    return False, default


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _bounds(low, high, above, below) -> str:
    parts = [f">= {low:g}" if low is not None else "", f"> {above:g}" if above is not None else "",
             f"<= {high:g}" if high is not None else "", f"< {below:g}" if below is not None else ""]
    return " and ".join(part for part in parts if part)


def _check_number(value, label: str, where: str, whole: bool, low, high, above, below) -> float | int:
    kind = "a whole number" if whole else "a finite number"
    limits = _bounds(low, high, above, below)
    good = (isinstance(value, int) and not isinstance(value, bool)) if whole else \
        (_is_number(value) and math.isfinite(value))
    if not good:
        raise DataFileError(f"{where}: {label} must be {kind} {limits}".rstrip() + f", got {_show(value)}")
    if (low is not None and value < low) or (high is not None and value > high) \
            or (above is not None and value <= above) or (below is not None and value >= below):
        raise DataFileError(f"{where}: {label} must be {limits}, got {value!r}")
    return int(value) if whole else float(value)


def number(table: dict, key: str, where: str, default=REQUIRED, low=None, high=None, above=None,
           below=None) -> float:
    """A finite number (int or float) within the inclusive ``low``/``high`` and exclusive ``above``/``below``."""
    present, value = _present(table, key, where, default)
    return _check_number(value, f"'{key}'", where, False, low, high, above, below) if present else value


def integer(table: dict, key: str, where: str, default=REQUIRED, low=None, high=None) -> int:
    """A whole number within ``low``..``high`` (inclusive)."""
    present, value = _present(table, key, where, default)
    return int(_check_number(value, f"'{key}'", where, True, low, high, None, None)) if present else value


def text(table: dict, key: str, where: str, default=REQUIRED, choices: Iterable[str] | None = None,
         nonempty: bool = True) -> str:
    """A string (non-empty unless told), one of ``choices`` when given."""
    present, value = _present(table, key, where, default)
    if not present:
        return value
    if not isinstance(value, str) or (nonempty and not value.strip()):
        raise DataFileError(f"{where}: '{key}' must be a {'non-empty ' if nonempty else ''}string, got {_show(value)}")
    if choices is not None and value not in tuple(choices):
        raise DataFileError(f"{where}: {key} '{value}' is not one of {', '.join(choices)}")
    return value


def flag(table: dict, key: str, where: str, default=REQUIRED) -> bool:
    """A boolean (``true`` or ``false``)."""
    present, value = _present(table, key, where, default)
    if present and not isinstance(value, bool):
        raise DataFileError(f"{where}: '{key}' must be true or false, got {_show(value)}")
    return value


def numbers(table: dict, key: str, where: str, default=REQUIRED, length: int | None = None, low=None, high=None,
            above=None, whole: bool = False, nonempty: bool = True) -> tuple:
    """A list of finite numbers (whole numbers with ``whole``), of ``length`` items when given."""
    present, value = _present(table, key, where, default)
    if not present:
        return value
    size = f"{length} " if length is not None else ""
    kind = "whole numbers" if whole else "numbers"
    if not isinstance(value, list) or (length is not None and len(value) != length) or (nonempty and not value):
        raise DataFileError(f"{where}: '{key}' must be a {'non-empty ' if nonempty and length is None else ''}"
                            f"list of {size}{kind}, got {_show(value)}")
    return tuple(_check_number(item, f"item {index + 1} of '{key}'", where, whole, low, high, above, None)
                 for index, item in enumerate(value))


def value_range(table: dict, key: str, where: str, default=REQUIRED, low=None, high=None) -> tuple[float, float]:
    """``[low, high]``: two finite numbers, the first not above the second, both within the bounds."""
    present, value = _present(table, key, where, default)
    if not present:
        return value
    first, second = numbers(table, key, where, length=2, low=low, high=high)
    if first > second:
        raise DataFileError(f"{where}: '{key}' must be [low, high] with low <= high, got {[first, second]}")
    return first, second


def texts(table: dict, key: str, where: str, default=REQUIRED, nonempty: bool = False,
          choices: Iterable[str] | None = None) -> tuple[str, ...]:
    """A list of non-empty strings (at least one with ``nonempty``), each one of ``choices`` when given."""
    present, value = _present(table, key, where, default)
    if not present:
        return tuple(value)
    if not isinstance(value, list) or not all(isinstance(v, str) and v.strip() for v in value) \
            or (nonempty and not value):
        raise DataFileError(f"{where}: '{key}' must be a {'non-empty ' if nonempty else ''}list of names, "
                            f"got {_show(value)}")
    if choices is not None:
        choices = tuple(choices)
        unknown = [v for v in value if v not in choices]
        if unknown:
            raise DataFileError(f"{where}: '{key}' names '{unknown[0]}'; accepted: {', '.join(choices)}")
    return tuple(value)


def section(table: dict, key: str, where: str, default=REQUIRED) -> dict:
    """A sub-table ``[key]`` (``default`` when absent and optional)."""
    present, value = _present(table, key, where, default)
    if present and not isinstance(value, dict):
        raise DataFileError(f"{where}: '{key}' must be a table [{key}], got {_show(value)}")
    return value


def tables(table: dict, key: str, where: str, default=REQUIRED, nonempty: bool = False) -> list[dict]:
    """An array of tables ``[[key]]``."""
    present, value = _present(table, key, where, default)
    if not present:
        return list(value)
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value) or (nonempty and not value):
        raise DataFileError(f"{where}: '{key}' must be {'one or more' if nonempty else 'a list of'} [[{key}]] "
                            f"tables, got {_show(value)}")
    return value
