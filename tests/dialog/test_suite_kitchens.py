"""An episodes suite run in several kitchens (``kitchens = [...]``, issue 52): a run in each, then the
strategies' ranks per kitchen and Kendall's W across them (dialog/experiments/kitchens.py)."""

from __future__ import annotations

import json

import pytest

from dialog.cli import main
from dialog.experiments.suite import SuiteError, load_suite
from learning.strategies import STRATEGY_NAMES

ACROSS = 'extends = "smoke"\nname = "smoke-kitchens"\nkitchens = ["kitchen-1", "kitchen-2"]\n'


def test_a_suite_runs_in_each_kitchen_and_ranks_the_strategies_across_them(tmp_path, capsys):
    path = tmp_path / "across.toml"
    path.write_text(ACROSS)
    out = tmp_path / "out"
    assert main(["regress", "--suite", str(path), "--results", str(out), "--no-progress", "--datasets", "1",
                 "--strategies", "passive", "dt-task", "--data-seeds", "0", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["kitchens"] == ["kitchen-1", "kitchen-2"] and "static" in summary["kendalls_w"]
    for kitchen in ("kitchen-1", "kitchen-2"):
        assert (out / f"kitchen-{kitchen}" / "replication.json").exists()
    rankings = json.loads((out / "kitchens.json").read_text())["conditions"]["static"]
    assert rankings["kitchens"] == ["kitchen-1", "kitchen-2"] and rankings["strategies"] == ["passive", "dt-task"]
    for means, ranks in zip(rankings["means"], rankings["ranks"]):
        assert sorted(ranks) == [1.0, 2.0] or ranks == [1.5, 1.5]
        assert (means[0] > means[1]) == (ranks[0] < ranks[1])
    assert "Kendall's W" in (out / "kitchens.md").read_text()


def test_the_kitchens_of_a_suite_may_be_a_generator_seed_range(tmp_path, monkeypatch):
    monkeypatch.setenv("TEACHBOT_CACHE", str(tmp_path))
    path = tmp_path / "range.toml"
    path.write_text('extends = "smoke"\nname = "r"\nkitchens = { generated = [9001, 9002], also = ["kitchen-3"] }\n')
    suite = load_suite(path, STRATEGY_NAMES)
    assert [k.rsplit("/", 1)[-1] for k in suite.kitchens] == ["generated-9001.toml", "generated-9002.toml",
                                                              "kitchen-3"]
    assert suite.kitchen == suite.kitchens[0]


@pytest.mark.parametrize("text, message", [
    (ACROSS.replace('kitchens = ["kitchen-1", "kitchen-2"]', 'kitchens = ["kitchen-1", "kitchen-1"]'),
     "'kitchens' names a kitchen twice"),
    (ACROSS.replace('kitchens = ["kitchen-1", "kitchen-2"]', 'kitchens = { generated = [3] }'),
     "'kitchens' as a table must be { generated = [FIRST, LAST] }"),
    ('name = "x"\nkind = "recipes"\nstrategies = ["situated"]\ncheckpoints = [1]\nkitchens = ["kitchen-1"]\n',
     "a recipes suite lists its kitchens under [options]"),
])
def test_bad_kitchens_get_one_clear_line(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SuiteError, match=message.replace("[", r"\[").replace("]", r"\]").replace("{", r"\{")
                       .replace("}", r"\}")):
        load_suite(path, STRATEGY_NAMES)


def test_check_and_baselines_are_refused_across_kitchens(tmp_path, capsys):
    path = tmp_path / "across.toml"
    path.write_text(ACROSS)
    assert main(["regress", "--suite", str(path), "--results", str(tmp_path / "o"), "--check"]) == 2
    assert "runs in 2 kitchens; --check compares or stores one run" in capsys.readouterr().err
