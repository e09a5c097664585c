"""Reading and validating the TOML data files under ``bullet_world/data/``, and the on-disk cache.

Every check raises :class:`DataFileError` with a one-line message naming the
file, the field, and what is accepted.
"""

from __future__ import annotations

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
import os
from pathlib import Path

DATA_DIR = Path(__file__).parent / "data"
CACHE_ENV = "TEACHBOT_CACHE"


class DataFileError(ValueError):
    """A kitchen, task or object file is missing, malformed or inconsistent."""


def read_toml(path: Path) -> dict:
    try:
        with open(path, "rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        raise DataFileError(f"{path}: no such file") from None
    except tomllib.TOMLDecodeError as error:
        raise DataFileError(f"{path}: not valid TOML ({error})") from None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def field(table: dict, key: str, where: str, kind: type | tuple = (int, float), length: int | None = None):
    """Return ``table[key]`` after checking its type (and, for number lists, its length)."""
    if key not in table:
        raise DataFileError(f"{where}: missing field '{key}'")
    value = table[key]
    if length is not None:
        if not isinstance(value, list) or len(value) != length or not all(_is_number(v) for v in value):
            raise DataFileError(f"{where}: '{key}' must be a list of {length} numbers, got {value!r}")
        return [float(v) for v in value]
    if kind == (int, float) and not _is_number(value):
        raise DataFileError(f"{where}: '{key}' must be a number, got {value!r}")
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise DataFileError(f"{where}: '{key}' has the wrong type ({type(value).__name__}), got {value!r}")
    return value


def optional(table: dict, key: str, where: str, default, kind: type | tuple = (int, float), length: int | None = None):
    """Like :func:`field` but returns ``default`` when the key is absent."""
    return field(table, key, where, kind, length) if key in table else default


def number_range(table: dict, key: str, where: str) -> tuple[float, float]:
    low, high = field(table, key, where, length=2)
    if not 0 <= low <= high:
        raise DataFileError(f"{where}: '{key}' must be [low, high] with 0 <= low <= high, got {[low, high]}")
    return low, high


def colour_list(table: dict, key: str, where: str) -> tuple[tuple[float, float, float], ...]:
    """A non-empty list of [r, g, b] colours with channels in 0..1."""
    colours = field(table, key, where, list)
    if not colours:
        raise DataFileError(f"{where}: '{key}' must list at least one [r, g, b]")
    result = []
    for colour in colours:
        rgb = field({key: colour}, key, where, length=3)
        if not all(0.0 <= c <= 1.0 for c in rgb):
            raise DataFileError(f"{where}: colours in '{key}' must have channels in 0..1, got {colour}")
        result.append(tuple(rgb))
    return tuple(result)


def string_list(table: dict, key: str, where: str, default=()) -> tuple[str, ...]:
    if key not in table:
        return tuple(default)
    value = table[key]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise DataFileError(f"{where}: '{key}' must be a list of names, got {value!r}")
    return tuple(value)


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


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file so readers never see half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    temporary.write_bytes(data)
    os.replace(temporary, path)
