"""Reading the TOML data files of ``learning`` (recipes, weights) with one-line errors that name the file."""

from __future__ import annotations

from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib


def read_toml(path: str | Path, what: str) -> dict:
    """The parsed file; FileNotFoundError "<what> file <path> does not exist", ValueError when it is not TOML."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{what} file {path} does not exist")
    try:
        with path.open("rb") as handle:
            return tomllib.load(handle)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: not valid TOML ({error})") from None
