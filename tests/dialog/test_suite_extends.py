"""A suite that extends a thesis suite (issue 39's pre-registered run): the base's episodes, more strategies and
findings, nothing else (dialog/experiments/suite.py ``_extended``)."""

import pytest

from dialog.experiments.suite import SuiteError, load_suite
from learning.strategies import STRATEGY_NAMES


def write(tmp_path, text):
    path = tmp_path / "extension.toml"
    path.write_text(text)
    return path


EXTENSION = '''extends = "ch7-pack-lunchbox"
name = "ext"
add_strategies = ["dt-voi"]

[[finding]]
id = "voi"
text = "dt-voi is not worse than active"
condition = "both-constrained"
at = 40
better = "dt-voi"
than = ["active"]
margin = 0.01
'''


def test_an_extension_plays_the_base_suites_episodes_with_more_strategies_and_findings(tmp_path):
    base, extended = load_suite("ch7-pack-lunchbox"), load_suite(write(tmp_path, EXTENSION), STRATEGY_NAMES)
    assert extended.name == "ext" and extended.strategies == (*base.strategies, "dt-voi")
    assert extended.conditions == base.conditions and extended.costs == base.costs
    assert extended.checkpoints == base.checkpoints and extended.datasets == base.datasets
    assert extended.findings[:len(base.findings)] == base.findings
    assert extended.findings[-1].id == "voi" and extended.findings[-1].margin == 0.01


@pytest.mark.parametrize("change, message", [
    (('extends = "ch7-pack-lunchbox"', 'extends = "ch7-pack"'), "extends 'ch7-pack', which is not a suite"),
    (('add_strategies = ["dt-voi"]', 'add_strategies = ["active"]'), "add_strategies repeats ['active']"),
    (('name = "ext"', 'name = "ext"\nbudget = 3'), "budget"),
    (('than = ["active"]', 'than = ["nobody"]'), "strategies ['nobody'] are not in the suite's strategies"),
])
def test_a_bad_extension_gets_one_clear_line(tmp_path, change, message):
    old, new = change
    with pytest.raises(SuiteError, match=message.replace("[", r"\[").replace("]", r"\]")):
        load_suite(write(tmp_path, EXTENSION.replace(old, new, 1)), STRATEGY_NAMES)


@pytest.mark.parametrize("name", ["prereg-ch6-static", "prereg-ch6-dynamic", "prereg-ch7", "prereg-ch7-pack-lunchbox",
                                  "prereg-embodied"])
def test_the_preregistered_suites_extend_their_thesis_suite(name):
    extended, base = load_suite(name), load_suite(name.removeprefix("prereg-"))
    assert extended.conditions == base.conditions and "dt-voi" in extended.strategies
    assert {f.id for f in base.findings} <= {f.id for f in extended.findings}


def test_an_extension_may_move_to_another_kitchen_and_keep_only_some_conditions(tmp_path):
    """Issue 52's rankings across kitchens: the base's episodes in another kitchen, one condition, its findings,
    and only the checkpoints that condition reaches."""
    path = write(tmp_path, 'extends = "ch7"\nname = "ch7-elsewhere"\nkitchen = "kitchen-2"\n'
                           'only_conditions = ["both-constrained"]\nadd_strategies = ["dt-voi"]\n')
    base, moved = load_suite("ch7"), load_suite(path, STRATEGY_NAMES)
    assert moved.kitchen == "kitchen-2" and base.kitchen == "kitchen-1"
    assert moved.conditions == tuple(c for c in base.conditions if c.name == "both-constrained")
    assert [f.id for f in moved.findings] == [f.id for f in base.findings if f.condition == "both-constrained"]
    assert moved.checkpoints == (10, 20, 30, 40) and moved.strategies == (*base.strategies, "dt-voi")


def test_only_conditions_names_the_base_suites_conditions(tmp_path):
    path = write(tmp_path, 'extends = "ch7"\nname = "x"\nonly_conditions = ["both-constrainted"]\n')
    with pytest.raises(SuiteError, match=r"only_conditions names \['both-constrainted'\], not conditions of suite "
                                         r"'ch7'; its conditions: time-constrained, unconstrained"):
        load_suite(path, STRATEGY_NAMES)
