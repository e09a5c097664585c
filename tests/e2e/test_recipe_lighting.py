"""``teachbot recipe`` lighting end to end: alternating demonstrations; an unseen lighting's failure is explained."""

import json

import pytest

from dialog.cli import main

pytestmark = pytest.mark.e2e


def test_demonstrations_alternate_the_lighting_by_default(capsys):
    assert main(["recipe", "--demos", "2", "--json"]) == 0
    out = capsys.readouterr().out
    assert "demo  1 (daylight)" in out and "demo  2 (evening)" in out
    assert "hint" not in json.loads(out.strip().splitlines()[-1])


def test_an_execution_under_a_lighting_no_demonstration_had_says_so(capsys):
    assert main(["recipe", "--demos", "2", "--demo-lighting", "daylight", "--execute", "--lighting", "evening",
                 "--json"]) == 0
    out = capsys.readouterr().out
    assert "demo  2 (daylight)" in out and "under evening lighting" in out
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["success"] is False
    assert "the object models never saw how the objects look under evening light" in summary["hint"]
    assert summary["hint"] in out
