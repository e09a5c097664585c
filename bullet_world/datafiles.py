"""Reading and validating the TOML data files under ``bullet_world/data/``, and the on-disk cache.

Reading and the field checks are the shared layer :mod:`learning.datafiles`; every
problem is a :class:`learning.errors.DataFileError` naming the file, the field and
what is accepted.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

try:
    import fcntl
except ImportError:  # not on POSIX
    fcntl = None  # type: ignore[assignment]

from learning.datafiles import numbers
from learning.datafiles import read_toml as read_data_file
from learning.errors import DataFileError

__all__ = ["CACHE_ENV", "DATA_DIR", "DataFileError", "available", "cache_dir", "colour_list", "one_builder",
           "read_toml", "resolve", "write_atomically"]

DATA_DIR = Path(__file__).parent / "data"
CACHE_ENV = "TEACHBOT_CACHE"


def read_toml(path: Path, what: str = "data") -> dict:
    """A data file parsed by the shared layer (:func:`learning.datafiles.read_toml`)."""
    return read_data_file(path, what)


def colour_list(table: dict, key: str, where: str) -> tuple[tuple[float, float, float], ...]:
    """A non-empty list of [r, g, b] colours with channels in 0..1."""
    colours = table.get(key)
    if key not in table:
        raise DataFileError(f"{where}: missing field '{key}'")
    if not isinstance(colours, list) or not colours:
        raise DataFileError(f"{where}: '{key}' must list at least one [r, g, b] colour, got {colours!r}")
    result = tuple(numbers({key: colour}, key, f"{where} colour {index + 1}", length=3)
                   for index, colour in enumerate(colours))
    for colour in result:
        if not all(0.0 <= channel <= 1.0 for channel in colour):
            raise DataFileError(f"{where}: colours in '{key}' must have channels in 0..1, got {list(colour)}")
    return result


def available(folder: str) -> list[str]:
    return sorted(p.stem for p in (DATA_DIR / folder).glob("*.toml"))


def resolve(folder: str, name_or_path: str | Path) -> Path:
    """``data/<folder>/<name>.toml`` for a name, or the path itself for a ``.toml`` path."""
    path = Path(name_or_path)
    if path.suffix == ".toml":
        return path
    candidate = DATA_DIR / folder / f"{name_or_path}.toml"
    if not candidate.exists():
        raise DataFileError(f"unknown {folder[:-1]} '{name_or_path}'; available: {', '.join(available(folder))}")
    return candidate


def cache_dir(override: str | Path | None = None) -> Path:
    """Where generated meshes, textures and data sets live: ``override``, $TEACHBOT_CACHE,
    $XDG_CACHE_HOME/teachbot, or ~/.cache/teachbot (created on demand)."""
    if override is not None:
        path = Path(override)
    elif os.environ.get(CACHE_ENV):
        path = Path(os.environ[CACHE_ENV])
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
        path = base / "teachbot"
    path.mkdir(parents=True, exist_ok=True)
    return path


@contextmanager
def one_builder(lock: Path) -> Iterator[None]:
    """Hold the exclusive lock file ``lock`` while a cached file is built: two processes that need the same file
    (two test workers, two ``regress`` runs) build it once, the second waiting and then reading it."""
    lock.parent.mkdir(parents=True, exist_ok=True)
    if fcntl is None:  # no advisory locks here: both may build, and write_atomically keeps the file whole
        yield
        return
    with open(lock, "a+b") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file so readers never see half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    temporary.write_bytes(data)
    os.replace(temporary, path)
