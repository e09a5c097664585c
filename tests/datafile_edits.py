"""Editing a shipped data file in a test, and expecting its loader to refuse the edit in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from learning.errors import DataFileError


def changed(text: str, old: str, new: str) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


def refused(loader, path: Path, *fragments: str) -> str:
    """Load ``path``, expect a one-line DataFileError naming the file and every fragment."""
    with pytest.raises(DataFileError) as caught:
        loader(path)
    message = str(caught.value)
    assert "\n" not in message and str(path) in message, message
    for fragment in fragments:
        assert fragment in message, message
    return message
