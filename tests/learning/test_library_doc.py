"""docs/library.md and the README's library example run as written: their examples are doctests."""

import doctest
from pathlib import Path

DOC = Path(__file__).resolve().parents[2] / "docs" / "library.md"
README = DOC.parents[1] / "README.md"


def test_the_library_page_examples_run_as_written():
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testfile(str(DOC), module_relative=False, optionflags=flags, verbose=False)
    assert result.attempted > 20
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples in {DOC.name} failed (see the output)"


def test_the_readme_library_example_runs_as_written():
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testfile(str(README), module_relative=False, optionflags=flags, verbose=False)
    assert result.attempted >= 8
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples in the README failed (see the output)"


def test_the_worked_strategy_example_is_the_shipped_module():
    """The page shows learning/strategies/examples.py's code (after its docstring) as it is."""
    import re

    shown = re.search(r"```python\n(import numpy as np\n.*?)```", DOC.read_text(), re.S)
    source = (DOC.parents[1] / "learning" / "strategies" / "examples.py").read_text()
    assert shown and shown.group(1) in source and source.endswith(shown.group(1))
