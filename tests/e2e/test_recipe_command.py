"""``teachbot recipe`` end to end: demonstrations in PyBullet, grounding, and the arm carrying the recipe out."""

import json

import pytest

from dialog.cli import main

pytestmark = pytest.mark.e2e


def test_recipe_command_learns_and_carries_out_serve_salad(capsys):
    code = main(["recipe", "--recipe", "serve-salad", "--kitchen", "1", "--demos", "4", "--execute", "--json",
                 "--seed", "3"])
    out = capsys.readouterr().out
    assert code == 0
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["moved_object_found"] == "8/8"
    assert set(summary["parameters"]) == {"bowl", "salad-dressing", "cupboard", "fridge", "counter"}
    assert [step["status"] for step in summary["steps"]] == ["done", "done"]
    assert all(step["correct_object"] and step["in_true_end_region"] for step in summary["steps"])
    assert summary["success"] is True and all(step["sim_seconds"] > 3 for step in summary["steps"])
    assert "Parameter models (GMM, k chosen by BIC" in out and "2 of 2 steps carried out correctly" in out


@pytest.mark.parametrize("arguments, message", [
    (["--recipe", "serve-soup"], "unknown built-in recipe 'serve-soup'; accepted: serve-pasta, serve-salad"),
    (["--recipe", "serve-salad", "--task", "pack-lunchbox"], "has no [recipe_scenes] table"),
])
def test_bad_recipe_input_gets_a_one_line_message(capsys, arguments, message):
    assert main(["recipe", "--demos", "1", *arguments]) == 2
    error = capsys.readouterr().err.strip()
    assert message in error and len(error.splitlines()) == 1


def test_an_unknown_kitchen_is_refused_before_any_work(capsys):
    with pytest.raises(SystemExit) as raised:
        main(["recipe", "--demos", "1", "--kitchen", "9"])
    assert raised.value.code == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("teachbot recipe: --kitchen: no kitchen '9'; accepted: kitchen-1, kitchen-2, kitchen-3")
    assert len(error.splitlines()) == 1


def test_zero_demonstrations_are_refused(capsys):
    with pytest.raises(SystemExit):
        main(["recipe", "--demos", "0"])
    assert "expected a whole number of at least 1" in capsys.readouterr().err
