"""One writer per transcript: an exclusive ``flock`` on the transcript file, held for the whole session.

The kernel drops the lock when its process ends, however it ends, so a lock
left by a dead process can't block anyone: there is nothing stale to clean up.
The process that loses gets one line naming the file and the holder (its pid
and command, read from ``/proc/locks`` where the system has one).
"""

from __future__ import annotations

import errno
import fcntl
import os
from pathlib import Path

from dialog.output_paths import check_writable, writing
from learning.errors import TranscriptError


class TranscriptLock:
    """Open ``path`` for appending (created unless ``create=False``) and hold an exclusive lock on it.

    ``fd`` is the open descriptor (``O_APPEND``); the writer writes through it.
    ``release()`` (idempotent) closes it, which frees the lock.
    """

    def __init__(self, path: str | Path, *, create: bool = True):
        self.path = Path(path)
        check_writable(self.path, "transcript")
        with writing(self.path, "transcript"):
            if create:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_APPEND | (os.O_CREAT if create else 0), 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = lock_holder(fd)
            os.close(fd)
            raise TranscriptError(f"{self.path} is in use by another teachbot process ({holder}); wait until it "
                                  "ends or choose another --transcript") from None
        except OSError as error:
            if error.errno not in (errno.ENOLCK, errno.EOPNOTSUPP, errno.EINVAL):
                os.close(fd)
                raise
            # a file system without flock (some network mounts): go on unlocked rather than refuse to work
        self.fd: int | None = fd

    @property
    def held(self) -> bool:
        return self.fd is not None

    def size(self) -> int:
        return os.fstat(self.fd).st_size

    def release(self) -> None:
        if self.fd is not None:
            fd, self.fd = self.fd, None
            os.close(fd)

    def __enter__(self) -> TranscriptLock:
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def lock_holder(fd: int) -> str:
    """``pid 1234: teachbot teach ...`` for the process holding a flock on ``fd``'s file, as far as it can be told."""
    stat = os.fstat(fd)
    device = (os.major(stat.st_dev), os.minor(stat.st_dev))
    try:
        with open("/proc/locks", encoding="ascii", errors="replace") as handle:
            lines = handle.read().splitlines()
    except OSError:
        return "its pid is unknown on this system"
    for line in lines:
        fields = line.split()
        if len(fields) < 6 or fields[1] != "FLOCK" or fields[3] != "WRITE":
            continue
        try:
            major, minor, inode = fields[5].split(":")
            same = (int(major, 16), int(minor, 16)) == device and int(inode) == stat.st_ino
            pid = int(fields[4])
        except ValueError:
            continue
        if same:
            return f"pid {pid}{_command(pid)}"
    return "pid unknown"


def _command(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as handle:
            words = handle.read().rstrip(b"\0").split(b"\0")
    except OSError:
        return ""
    names = [os.path.basename(word) for word in words]
    start = names.index(b"teachbot") if b"teachbot" in names else 0  # "python .../bin/teachbot teach ...": from there
    words = [names[start], *words[start + 1:]] if words and words[0] else []
    text = " ".join(word.decode("utf-8", "replace") for word in words)
    return f": {text[:100]}{'...' if len(text) > 100 else ''}" if text else ""
