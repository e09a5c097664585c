"""Recipe lighting: demonstrations alternate the conditions, bad lighting is refused first, a failure says why."""

from types import SimpleNamespace

import pytest

from dialog.cli import main
from dialog.recipe_session import check_lighting, demonstration_lighting, lighting_hint
from learning.errors import SettingsError

CONDITIONS = ["daylight", "evening"]


def sweep_order(count, per_sweep=6):
    """(layout, condition) of each demonstration in ``RecipeWorld.demonstrate``'s sweep order."""
    out = []
    for number in range(count):
        round_, within = divmod(number, per_sweep * len(CONDITIONS))
        out.append((round_ * per_sweep + within % per_sweep, CONDITIONS[within // per_sweep]))
    return out


def test_alternate_changes_the_light_with_every_arrangement_and_keeps_every_pair_once():
    lights = [demonstration_lighting("alternate", CONDITIONS, layout, swept) for layout, swept in sweep_order(12)]
    assert lights[:5] == ["daylight", "evening", "daylight", "evening", "daylight"]
    pairs = {(layout, light) for (layout, _), light in zip(sweep_order(12), lights)}
    assert len(pairs) == 12  # each of the 6 arrangements under both conditions, as in the sweep order


def test_sweep_and_a_named_condition():
    assert [demonstration_lighting("sweep", CONDITIONS, layout, swept) for layout, swept in sweep_order(5)] \
        == ["daylight"] * 5
    assert demonstration_lighting("evening", CONDITIONS, 3, "daylight") == "evening"
    with pytest.raises(SettingsError, match="accepted: alternate, sweep, daylight, evening"):
        demonstration_lighting("dusk", CONDITIONS, 0, "daylight")


@pytest.mark.parametrize("execution, demos, fragment", [
    ("dusk", "alternate", "--lighting 'dusk': the task's lighting conditions are daylight, evening"),
    (None, "dusk", "--demo-lighting 'dusk': accepted are alternate, sweep or one of the task's lighting"),
])
def test_check_lighting_names_what_is_accepted(execution, demos, fragment):
    with pytest.raises(SettingsError) as error:
        check_lighting(CONDITIONS, execution, demos)
    assert fragment in str(error.value)
    check_lighting(CONDITIONS, "evening", "daylight")  # good ones pass


def outcome(success):
    return SimpleNamespace(success=success)


def test_the_hint_only_when_a_step_failed_under_a_lighting_no_demonstration_had():
    daylight_only = [SimpleNamespace(lighting="daylight")] * 3
    hint = lighting_hint(daylight_only, "evening", [outcome(False), outcome(True)])
    assert "never saw" in hint and "evening" in hint and "--lighting daylight" in hint and "1 of 2 steps" in hint
    assert lighting_hint(daylight_only, "evening", [outcome(True)]) is None
    both = [SimpleNamespace(lighting="daylight"), SimpleNamespace(lighting="evening")]
    assert lighting_hint(both, "evening", [outcome(False)]) is None


@pytest.mark.parametrize("arguments, fragment", [
    (["--lighting", "dusk"], "--lighting 'dusk': the task's lighting conditions are daylight, evening"),
    (["--demo-lighting", "night"], "--demo-lighting 'night'"),
])
def test_bad_lighting_is_refused_before_the_kitchen_is_built(monkeypatch, capsys, arguments, fragment):
    def no_world(*args, **kwargs):
        raise AssertionError("the kitchen was built before the arguments were checked")

    monkeypatch.setattr("dialog.commands.recipe.NarratedRecipeWorld", no_world)
    assert main(["recipe", "--execute", *arguments]) == 2
    error = capsys.readouterr().err.strip()
    assert fragment in error and len(error.splitlines()) == 1
