"""Every ``--json`` line and JSON report a command writes is strict JSON: no ``NaN``/``Infinity`` (issue 42, case 3)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from dialog.cli import main
from dialog.commands._json import print_json, strict_json

COMMANDS = Path(__file__).resolve().parents[2] / "dialog" / "commands"


def refuse_constant(name):
    raise ValueError(f"not JSON: {name}")


def strict(text: str):
    return json.loads(text, parse_constant=refuse_constant)


def test_a_number_that_is_not_finite_is_printed_as_null(capsys):
    print_json({"log_likelihood": float("-inf"), "spread": [float("nan"), 1.5, (float("inf"), 2)], "n": 3})
    assert strict(capsys.readouterr().out) == {"log_likelihood": None, "spread": [None, 1.5, [None, 2]], "n": 3}
    assert strict(strict_json({"a": float("nan")}, indent=1)) == {"a": None}


def test_every_command_writes_json_through_the_one_printer():
    direct = [path.name for path in COMMANDS.glob("*.py")
              if path.name != "_json.py" and re.search(r"\bjson\.dumps\(", path.read_text())]
    assert direct == [], f"{direct} print JSON with json.dumps; use dialog.commands._json.print_json"


def test_learn_weights_help_names_imitation_as_the_default(capsys):
    with pytest.raises(SystemExit):
        main(["learn-weights", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "By default (--method imitation)" in text and "By default the trajectory" not in text


@pytest.mark.e2e
def test_learn_weights_json_is_strict_where_a_baseline_never_asks(tmp_path, capsys):
    """The always-quiet baseline's log-likelihood is -inf (the experts ask): it was printed as -Infinity."""
    report = tmp_path / "report.json"
    assert main(["learn-weights", "--demos", "shipped", "--out", str(tmp_path / "w.toml"), "--split-seeds", "0",
                 "--fit-seeds", "0", "--iterations", "1", "--report", str(report), "--no-check", "--json"]) == 0
    summary = strict(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["baselines_on_kept_held_out"]["always_quiet"]["log_likelihood"] is None
    assert strict(report.read_text())["baselines_on_kept_held_out"]["always_quiet"]["log_likelihood"] is None
