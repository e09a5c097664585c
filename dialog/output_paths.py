"""Paths the tool writes: checked before the first turn, and every write error as one clear message.

``check_writable(path, what)`` refuses, up front, a path that is a folder, a
parent that is a file, a read-only or inaccessible folder and a full disk.
``writing(path, what)`` turns an ``OSError`` raised while writing into an
:class:`~learning.errors.OutputPathError` naming the path and the cause, e.g.
``runs/a.jsonl: cannot write the transcript: no space left on device (ENOSPC)``.
"""

from __future__ import annotations

import errno
import os
from contextlib import contextmanager
from pathlib import Path

from learning.errors import OutputPathError

#: errors that mean "this output can't be written here" (anything else from a write is a bug)
WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EROFS, errno.EISDIR, errno.EEXIST, errno.EACCES, errno.EPERM,
                          errno.ENOTDIR, errno.EDQUOT, errno.EFBIG, errno.ENAMETOOLONG, errno.EIO})


def cause(code: int) -> str:
    """``no space left on device (ENOSPC)`` for an errno."""
    return f"{os.strerror(code).lower()} ({errno.errorcode.get(code, code)})"


def output_error(path: str | Path, what: str, code: int, detail: str = "") -> OutputPathError:
    """The one-line message for ``path``; ``detail`` says more than the errno does (which parent, say)."""
    return OutputPathError(f"{path}: cannot write the {what}: {detail or cause(code)}")


def from_os_error(error: OSError, path: str | Path, what: str) -> OutputPathError:
    """The message for an ``OSError`` raised while writing ``path`` (or a file inside it)."""
    named = error.filename if error.filename not in (None, "") else path
    return output_error(named, what, error.errno or errno.EIO)


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
    if _holds_no_files(ancestor):
        return _refuse(path, what, errno.EACCES, f"{ancestor} is on a virtual file system of the kernel (such as "
                                                 "/proc or /sys), which holds no files; give a path on a disk")
    free = _free_bytes(ancestor)
    if free == 0:
        return _refuse(path, what, errno.ENOSPC)
    return path


def _holds_no_files(folder: Path) -> bool:
    """True on a file system with no storage at all (procfs, sysfs: zero blocks), which statvfs reports as full."""
    try:
        return os.statvfs(folder).f_blocks == 0
    except (OSError, AttributeError):
        return False


def _refuse(path: Path, what: str, code: int, detail: str = "") -> Path:
    raise output_error(path, what, code, detail)


def _read_only(folder: Path) -> bool:
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except (OSError, AttributeError):
        return False


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
