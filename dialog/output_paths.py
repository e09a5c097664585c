"""Paths the tool writes: checked before the first turn, and every write error as one clear message.

``check_writable(path, what)`` refuses, up front, a path that is a folder, a
parent that is a file, a read-only or inaccessible folder and a full disk; an
output file must be a regular file or new (a FIFO, a device or a socket is
refused without being opened), and a name too long for the file system, a
path over the system's limit and a loop of symbolic links each get their own
message. ``file_argument`` is the ``type=`` of every command-line option
naming an output file: ``newdir/`` (a trailing separator) is a folder, not a
file name. Every command checks its outputs this way before its work starts
and creates missing folders as it writes; a file named on the command line in a
missing folder outside the current folder (``/nonexistent/dir/t.jsonl``) is
refused by ``file_argument`` (one rule, docs/dialog.md). ``numbered(path)`` is the next free name for a
default output (``runs/demo-...-seed0-2.jsonl``), so no earlier run is replaced.
``writing(path, what)`` turns an ``OSError`` raised while writing into an
:class:`~learning.errors.OutputPathError` naming the path and the cause, e.g.
``runs/a.jsonl: cannot write the transcript: no space left on device (ENOSPC)``.
"""

from __future__ import annotations

import argparse
import errno
import os
import stat
from contextlib import contextmanager
from pathlib import Path

from learning.datafiles import lookup_problem
from learning.errors import OutputPathError

#: errors that mean "this output can't be written here" (anything else from a write is a bug)
WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EROFS, errno.EISDIR, errno.EEXIST, errno.EACCES, errno.EPERM,
                          errno.ENOTDIR, errno.EDQUOT, errno.EFBIG, errno.ENAMETOOLONG, errno.EIO})


def cause(code: int) -> str:
    """``no space left on device (ENOSPC)`` for an errno."""
    return f"{os.strerror(code).lower()} ({errno.errorcode.get(code, code)})"


def output_error(path: str | Path, what: str, code: int, detail: str = "") -> OutputPathError:
    """The one-line message for ``path``; ``detail`` says more than the errno does (which parent, say)."""
    return OutputPathError(f"{shown_path(path)}: cannot write the {what}: {detail or cause(code)}")


def shown_path(path: str | Path) -> str:
    """``path`` as a message shows it: in full up to 160 characters, else its start and end around "..."."""
    text = os.fspath(path)
    return text if len(text) <= 160 else f"{text[:80]}...{text[-60:]}"


def from_os_error(error: OSError, path: str | Path, what: str) -> OutputPathError:
    """The message for an ``OSError`` raised while writing ``path`` (or a file inside it)."""
    named = error.filename if error.filename not in (None, "") else path
    return output_error(named, what, error.errno or errno.EIO)


#: what a path that exists but is no regular file is, by its stat type
SPECIAL_FILES = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
                 (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def file_argument(text: str) -> Path:
    """``type=`` for an option naming an output file: refuses a trailing separator (``newdir/`` is a folder)."""
    if not text:
        raise argparse.ArgumentTypeError("needs a file path, got an empty one")
    if (text.endswith(os.sep) or (os.altsep and text.endswith(os.altsep))) and not os.path.isdir(text):
        raise argparse.ArgumentTypeError(f"{text!r} ends in '{os.sep}', so it names a folder; give a file path "
                                         f"such as {text.rstrip(os.sep) or 'runs'}{os.sep}out.jsonl")
    path = Path(text)
    if not path_problem(path) and not path.parent.is_dir() and not inside_current_folder(path.parent) \
            and _existing_ancestor(path.parent).is_dir():
        raise argparse.ArgumentTypeError(f"{text}: the folder {path.parent} does not exist (missing folders are "
                                         f"created only inside the current folder, {Path.cwd()}); create it first "
                                         f"or give a path in an existing folder")
    return path


def path_problem(path: str | Path) -> str:
    """Why ``path`` can't even be looked up ("" when it can): a name or a path too long, a loop of links
    (``learning.datafiles.lookup_problem``, which data files use too)."""
    return lookup_problem(path)


def special_file(path: str | Path) -> str:
    """``"a FIFO (named pipe)"`` when ``path`` exists and is not a regular file or a folder, else ``""``."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return ""
    for test, kind in SPECIAL_FILES:
        if test(mode):
            return kind
    return ""


def _existing_ancestor(path: Path) -> Path:
    ancestor = path
    while not ancestor.exists() and ancestor != ancestor.parent:
        if ancestor.is_symlink():  # a dangling link: writing through it creates its target's folders, maybe not
            break
        ancestor = ancestor.parent
    return ancestor


def _free_bytes(folder: Path) -> int | None:
    try:
        stats = os.statvfs(folder)
    except (OSError, AttributeError):
        return None
    blocks = stats.f_bfree if hasattr(os, "geteuid") and os.geteuid() == 0 else stats.f_bavail
    return blocks * stats.f_frsize


def check_writable(path: str | Path, what: str, *, folder: bool = False) -> Path:
    """Raise :class:`OutputPathError` unless ``path`` (a file, or a ``folder``) can be written; nothing is created.

    Checks: not a folder where a file is meant (or a file where a folder is), no parent
    that is a file, the nearest existing folder writable (not read-only, accessible),
    and some space left on its device.
    """
    path = Path(path)
    problem = path_problem(path)
    if problem:
        return _refuse(path, what, errno.ENAMETOOLONG, problem)
    kind = special_file(path)
    if kind:
        return _refuse(path, what, errno.EINVAL, f"it is {kind}, not a regular file; give the path of a file "
                                                 f"to write (nothing was opened)" if not folder else
                       f"it is {kind}, not a folder")
    if path.is_dir() and not folder:
        return _refuse(path, what, errno.EISDIR, "it is a folder; give a file path")
    if path.exists() and not path.is_dir() and folder:
        return _refuse(path, what, errno.ENOTDIR, "it is a file; give a folder")
    ancestor = _existing_ancestor(path if folder else path.parent)
    if ancestor.exists() and not ancestor.is_dir():
        return _refuse(path, what, errno.ENOTDIR, f"{ancestor} is a file, not a folder")
    target = path if path.exists() else ancestor
    if not os.access(target, os.W_OK):
        if _read_only(target):
            return _refuse(path, what, errno.EROFS, f"{target} is on a read-only file system (EROFS)")
        return _refuse(path, what, errno.EACCES, f"no permission to write {target} (EACCES)")
    if _pseudo_file_system(ancestor):
        return _refuse(path, what, errno.EINVAL, f"{ancestor} is on a file system of the kernel's (such as /proc or "
                                                 "/sys) that holds no files of yours; choose a folder on a disk")
    free = _free_bytes(ancestor)
    if free == 0:
        return _refuse(path, what, errno.ENOSPC)
    return path


def inside_current_folder(path: str | Path) -> bool:
    """True when ``path`` is the current folder or lies below it (where missing folders may be created)."""
    return Path(os.path.abspath(path)).is_relative_to(Path.cwd())


def numbered(path: str | Path) -> Path:
    """``path`` if nothing is there yet, else the first free ``NAME-2.EXT``, ``NAME-3.EXT``, ...: a default output
    name never replaces an earlier run's file (teach's and demo's transcripts, demo's episode page)."""
    path = Path(path)
    number = 2
    candidate = path
    while candidate.exists():
        candidate, number = path.with_name(f"{path.stem}-{number}{path.suffix}"), number + 1
    return candidate


def _pseudo_file_system(folder: Path) -> bool:
    """True for /proc, /sys and the like: a file system with no blocks at all (its "free space" is always 0)."""
    try:
        stats = os.statvfs(folder)
    except (OSError, AttributeError):
        return False
    return stats.f_blocks == 0 and stats.f_files == 0


def _refuse(path: Path, what: str, code: int, detail: str = "") -> Path:
    raise output_error(path, what, code, detail)


def _read_only(folder: Path) -> bool:
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except (OSError, AttributeError):
        return False


def superseded_name(path: str | Path) -> Path:
    """``FILE.superseded-N`` with the first N not taken: where a recorded file is kept when it is replaced."""
    path = Path(path)
    number = 1
    while path.with_name(f"{path.name}.superseded-{number}").exists():
        number += 1
    return path.with_name(f"{path.name}.superseded-{number}")


def keep_superseded(path: str | Path, what: str) -> Path | None:
    """Rename a recorded ``path`` that holds something to :func:`superseded_name` before it is replaced; returns
    the new name (None when there was nothing to keep). The caller says so."""
    path = Path(path)
    if not path.is_file() or path.stat().st_size == 0:
        return None
    target = superseded_name(path)
    with writing(path, what):
        path.rename(target)
    return target


def make_parent(path: str | Path, what: str) -> Path:
    """Create the missing folders above the output file ``path`` (the one rule: outputs are checked with
    :func:`check_writable` before the work starts, and their folders are created when they are written)."""
    path = Path(path)
    with writing(path, what):
        path.parent.mkdir(parents=True, exist_ok=True)
    return path


@contextmanager
def writing(path: str | Path, what: str, *, inside: bool = False):
    """Turn a write error (full disk, read-only, a folder, a file as parent, no access) into one message.

    With ``inside`` (``path`` is a folder of outputs) only errors about files in that
    folder, or naming no file, are converted; any other ``OSError`` keeps its traceback.
    """
    try:
        yield
    except OutputPathError:
        raise
    except OSError as error:
        if error.errno not in WRITE_ERRNOS or (inside and not _within(error.filename, path)):
            raise
        raise from_os_error(error, path, what) from None


def _within(filename, folder: str | Path) -> bool:
    if filename in (None, ""):
        return True
    try:
        return Path(os.path.abspath(filename)).is_relative_to(os.path.abspath(folder))
    except (TypeError, ValueError):
        return False
