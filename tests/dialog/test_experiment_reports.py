"""Suite kinds behind one registry; reports that say what they skip; figures told apart; rendering progress."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments import kinds, pools, registry
from dialog.experiments.analysis import BOOTSTRAP_SEED, compare, evaluate_findings, skipped_by_overrides, summarise
from dialog.experiments.baseline import make_baseline
from dialog.experiments.figures import learning_curve_figure, strategy_styles, timing_figure
from dialog.experiments.report import markdown_report
from dialog.experiments.runner import RenderBar
from dialog.experiments.suite import SuiteError, load_suite
from learning.significance import cluster_bootstrap_ci

SUITE = """
name = "reports"
description = "two conditions, one shorter than the last checkpoints"
strategies = ["passive", "active", "random"]
datasets = 4
checkpoints = [2, 4, 8]
axis = "turns"
[[condition]]
name = "short"
budget = 10
turns = 4
change_every = 2
[[condition]]
name = "long"
budget = 10
turns = 8
change_every = 2
[[finding]]
id = "late-in-short"
text = "passive beats active after 8 turns"
condition = "short"
at = 8
better = "passive"
than = ["active"]
[[finding]]
id = "late-in-long"
text = "passive beats active after 8 turns"
condition = "long"
at = 8
better = "passive"
than = ["active"]
[[finding]]
id = "random-loses"
text = "passive beats random"
condition = "long"
at = 4
better = "passive"
than = ["random"]
"""


def suite_file(tmp_path, text=SUITE):
    path = tmp_path / "reports.toml"
    path.write_text(text)
    return path


def episode(strategy, condition, turns, dataset, level, questions=None):
    """A fake episode result: accuracy rising to ``level``; ``questions`` asked (default: one per turn)."""
    asked = questions if questions is not None else list(range(1, turns + 1))
    accuracy = list(np.linspace(0.2, level, turns) + 0.01 * dataset)
    return {"spec": {"condition": {"name": condition, "turns": turns, "budget": turns}, "strategy": strategy,
                     "dataset": dataset, "seed": 0, "costs": ()},
            "series": {"turn": list(range(1, turns + 1)), "accuracy": accuracy, "questions": asked,
                       "label": asked, "demo": [0] * turns, "feature": [0] * turns, "spent": asked},
            "accuracy": accuracy[-1], "seconds": 0.01}


def fake_results(suite, seeds=(0, 1)):
    """Every strategy on the same data sets and seeds (paired, as a suite's episodes are)."""
    levels = {"passive": 0.9, "active": 0.6, "random": 0.4}
    results = [episode(strategy, condition.name, condition.turns, dataset, levels.get(strategy, 0.5))
               for condition in suite.conditions for strategy in suite.strategies for dataset in range(suite.datasets)
               for seed in seeds]
    for result, seed in zip(results, [s for _ in range(len(results) // len(seeds)) for s in seeds]):
        result["spec"]["seed"] = seed
        result["series"]["accuracy"] = [a + 0.001 * seed for a in result["series"]["accuracy"]]
    return results


def test_every_kind_is_registered_and_an_unknown_kind_lists_them(tmp_path, capsys):
    assert registry.kind_names()[:3] == ("episodes", "feature-selection", "recipes")
    assert all(kinds.get_kind(name).name == name for name in registry.kind_names())
    with pytest.raises(SuiteError, match="unknown suite kind 'nope'; registered kinds: episodes, "
                                         "feature-selection, recipes"):
        kinds.get_kind("nope")
    path = suite_file(tmp_path, 'kind = "nope"\n' + SUITE)
    assert main(["regress", "--suite", str(path), "--results", str(tmp_path / "out"), "--no-progress"]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and "'nope' is not one of episodes, feature-selection, recipes" in error


def test_a_registered_kind_is_run_by_the_command(tmp_path, capsys, monkeypatch):
    class Counting(kinds.SuiteKind):
        name = "counting"

        def run(self, suite, options):
            return kinds.SuiteRun(suite, list(suite.strategies), [], [], len(suite.strategies), 0.0)

        def report(self, run, folder):
            path = folder / "report.md"
            path.write_text("counted " + ", ".join(run.data))
            return [path]

    monkeypatch.setattr(registry, "_KINDS", dict(registry._KINDS))  # the registration ends with the test
    registry.register_kind(Counting)
    path = suite_file(tmp_path, 'name = "c"\nkind = "counting"\nstrategies = ["a", "b"]\ncheckpoints = [1]\n')
    assert main(["regress", "--suite", str(path), "--results", str(tmp_path / "out"), "--no-progress"]) == 0
    assert "c: 2 runs in 0.0 s" in capsys.readouterr().out
    assert (tmp_path / "out" / "report.md").read_text() == "counted a, b"


def test_the_registry_hands_out_only_suite_kinds(monkeypatch):
    """The registry names no suite type (issue 43: no import circle); get_kind checks what it hands out."""
    class NotAKind:
        name = "not-a-kind"

    monkeypatch.setattr(registry, "_KINDS", dict(registry._KINDS))
    registry.register_kind(NotAKind)
    with pytest.raises(TypeError, match="'not-a-kind' \\(NotAKind\\) is not a SuiteKind"):
        kinds.get_kind("not-a-kind")
    assert isinstance(kinds.get_kind("episodes"), kinds.SuiteKind)


def test_a_strategy_subset_reports_the_findings_it_skips_and_why(tmp_path):
    original = load_suite(suite_file(tmp_path))
    suite = original.with_overrides(strategies=["passive", "active"])
    skipped = skipped_by_overrides(original, suite)
    assert [o.finding.id for o in skipped] == ["random-loses"]
    assert skipped[0].verdict == "skipped: needs random, not among the strategies run (passive, active)"
    results = fake_results(suite)
    summaries = summarise(results, suite)
    findings = evaluate_findings(summaries, suite) + skipped
    report = markdown_report(suite, results, summaries, findings, 1.0, tmp_path, []).read_text()
    assert "Skipped findings (not tested in this run):" in report
    assert "- random-loses: passive beats random: skipped, needs random, not among the strategies run" in report
    assert "random-loses skipped: needs random" in report  # and in the summary line


def test_checkpoints_beyond_a_conditions_turns_are_left_out_and_headings_name_the_turn(tmp_path):
    suite = load_suite(suite_file(tmp_path))
    results = fake_results(suite)
    summaries = summarise(results, suite)
    assert {s.condition: s.checkpoints for s in summaries} == {"short": (2, 4), "long": (2, 4, 8)}
    findings = evaluate_findings(summaries, suite)
    by_id = {o.finding.id: o for o in findings}
    assert by_id["late-in-short"].skipped == "it compares after 8 turns, beyond the condition's 4 turns"
    assert by_id["late-in-long"].holds and not by_id["late-in-long"].skipped
    report = markdown_report(suite, results, summaries, findings, 1.0, tmp_path, []).read_text()
    short = report.split("## Condition `short`")[1].split("## Condition `long`")[0]
    long = report.split("## Condition `long`")[1].split("## The thesis's findings")[0]
    assert "| strategy | after 2 turns | after 4 turns | questions |" in short and "after 8" not in short
    assert "(checkpoints [8] lie beyond its 4 turns)" in short
    assert "two-sided tests between every pair of strategies after 4 turns." in short
    assert "| strategy | after 2 turns | after 4 turns | after 8 turns |" in long
    assert "two-sided tests between every pair of strategies after 8 turns." in long
    assert "(planned)" in report and "Holm" in report and "none (1 cluster)" in report  # all of data seed 0
    assert "late-in-short: passive beats active after 8 turns: skipped, it compares after 8 turns" in report
    assert "| late-in-long: passive beats active after 8 turns | long | 8 turns | passive > active |" in report
    bands = make_baseline(suite, summaries)["bands"]
    assert set(bands["short"]["passive"]) == {"2", "4"} and set(bands["long"]["passive"]) == {"2", "4", "8"}


def test_a_finding_at_a_point_that_is_no_checkpoint_is_refused_on_loading(tmp_path, capsys):
    path = suite_file(tmp_path, SUITE.replace("at = 4\n", "at = 5\n"))
    assert main(["regress", "--suite", str(path), "--results", str(tmp_path / "out"), "--no-progress"]) == 2
    error = capsys.readouterr().err.strip()
    assert "finding 'random-loses' compares at 5, which is not one of the checkpoints [2, 4, 8]" in error


def test_ten_strategies_get_distinct_styles_and_every_panel_a_legend(tmp_path):
    names = [f"strategy-{i}" for i in range(10)]
    styles = strategy_styles(names)
    assert len({s["color"] for s in styles.values()}) == 10
    assert len({(s["color"], s["linestyle"], s["marker"]) for s in styles.values()}) == 10
    assert len({s["linestyle"] for s in styles.values()}) >= 4
    suite = load_suite(suite_file(tmp_path)).with_overrides(strategies=names)
    long = suite.conditions[1]
    results = [episode(name, "long", 8, d, 0.5 + 0.04 * i, questions=[1, 2, 3, 4, 5, 6, 6 + (d > 0), 7 + (d > 0)])
               for i, name in enumerate(names) for d in range(3)]
    curves = learning_curve_figure(results, suite, long)
    assert len(curves.axes) == 2
    for axis in curves.axes:
        legend = axis.get_legend()
        assert legend is not None
        assert [t.get_text() for t in legend.get_texts()][:10] == names
        drawn = {line.get_label(): (line.get_color(), line.get_linestyle(), line.get_marker())
                 for line in axis.get_lines() if line.get_label() in names}
        assert len(set(drawn.values())) == 10
    # episodes 1 and 2 ask 8 questions, episode 0 only 7: the 8th is drawn faded and the legend says so
    assert "faded: fewer episodes reach it" in [t.get_text() for t in curves.axes[0].get_legend().get_texts()]
    assert "faded: fewer episodes reach it" not in [t.get_text() for t in curves.axes[1].get_legend().get_texts()]
    timing = timing_figure(results, suite, long)
    (axis,) = timing.axes
    assert axis.get_legend() is not None and len(axis.get_legend().get_texts()) == 10
    assert "in the episode of data set 0, seed 0" in axis.get_title()
    colours = {tuple(np.round(c.get_facecolor()[0], 3)) for c in axis.collections}
    assert len(colours) == 10
    (twenty,) = timing_figure(results, suite, dataclasses.replace(long, turns=20)).axes  # smoke's 20 turns
    ticks = twenty.xaxis.get_major_locator()()
    assert len(ticks) > 3 and all(float(t).is_integer() for t in ticks)  # there is no turn 2.5


def test_rendering_the_data_sets_reports_progress_with_the_time(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(pools, "load_datasets", functools.partial(pools.load_datasets, cache=tmp_path))
    monkeypatch.setattr(pools, "_loaded", {})
    plan = (("objects_per_scene", 8), ("pool_size", 12), ("test_size", 8))
    calls = []

    def listen(done, total, message):
        calls.append((done, total))
        bar(done, total, message)

    with RenderBar("pack-lunchbox/kitchen-1") as bar:
        first = pools.load_pools("pack-lunchbox", "kitchen-1", 1, plan, progress=listen)
    total = calls[0][1]
    assert calls == [(done, total) for done in range(1, total + 1)] and total >= 2
    assert "rendered the data sets of pack-lunchbox/kitchen-1 in " in capsys.readouterr().err
    monkeypatch.setattr(pools, "_loaded", {})
    calls.clear()
    with RenderBar("pack-lunchbox/kitchen-1") as bar:
        again = pools.load_pools("pack-lunchbox", "kitchen-1", 1, plan, progress=listen)
    assert calls == [] and capsys.readouterr().err == ""  # from the cache: no bar, no line
    assert np.array_equal(first.test.X, again.test.X)


def test_a_recipe_finding_without_trials_is_skipped_with_the_arms_it_misses():
    from dialog.experiments.recipes.suite import evaluate_recipe_findings

    suite = load_suite("recipes")
    outcomes = evaluate_recipe_findings([], suite)
    assert len(outcomes) == len(suite.findings) and not any(o.holds for o in outcomes)
    first = suite.findings[0]
    assert outcomes[0].skipped.startswith(f"no trials of {first.better} at m = {first.at}")


def test_report_headers_say_seeds_and_teachers_in_words():
    from dialog.experiments.report import numbers_in_words, teacher_in_words
    assert numbers_in_words((0, 1, 2, 3, 4)) == "0-4" and numbers_in_words((0, 2, 7)) == "0, 2, 7"
    assert numbers_in_words((3,)) == "3" and numbers_in_words((0, 1)) == "0, 1"
    assert teacher_in_words({}) == "scripted" and teacher_in_words({"kind": "oracle"}) == "oracle"
    assert teacher_in_words({"kind": "scripted", "mislabel_rate": 0.1}) == "scripted (mislabel rate 0.1)"


def test_the_interval_resamples_data_seeds_and_names_how_many(tmp_path):
    """The episodes of one data seed share its test pool: a data seed is one cluster, whatever its data sets and
    seeds; one data seed gives no interval (the other test of reports), three give three clusters."""
    suite = load_suite(suite_file(tmp_path))
    results = fake_results(suite)  # every data set x seeds 0-1, all of data seed 0
    episodes = suite.datasets * 2
    for result in results:
        result["spec"]["data_seed"] = (result["spec"]["dataset"] + result["spec"]["seed"]) % 3  # data seeds 0-2
    summaries = summarise(results, suite)
    long = [s for s in summaries if s.condition == "long"]
    comparison = compare(long[0], long[1], -1)
    assert comparison.n == episodes > 3 and comparison.clusters == 3 and comparison.ci is not None
    for result in results:
        result["spec"]["data_seed"] = 7 if result["spec"]["seed"] == 0 else 9
    summaries = summarise(results, suite)
    long = [s for s in summaries if s.condition == "long"]
    comparison = compare(long[0], long[1], -1)
    assert comparison.n == episodes and comparison.clusters == 2
    differences = long[0].values[:, -1] - long[1].values[:, -1]
    by_seed = [7 if key[2] == 0 else 9 for key in long[0].keys]
    assert comparison.ci == cluster_bootstrap_ci(differences, by_seed, np.random.default_rng(BOOTSTRAP_SEED))
    report = markdown_report(suite, results, summaries, evaluate_findings(summaries, suite), 1.0, tmp_path,
                             []).read_text()
    assert "(2 clusters)" in report and "none (1 cluster)" not in report


def test_a_margin_makes_a_paired_non_inferiority_test_and_reports_the_strategies_own_means():
    """Issue 40's findings: "not worse than, margin 0.01" tests first + 0.01 > second. A strategy 0.005 behind on
    every one of 25 pairs is non-inferior with the margin and not better without it; 0.02 behind fails both."""
    from dialog.experiments.analysis import CheckpointSummary

    keys = tuple((seed, dataset, 0) for seed in range(5) for dataset in range(5))
    base = np.linspace(0.6, 0.9, 25)[:, None]
    jitter = np.random.default_rng(0).uniform(-0.001, 0.001, (25, 1))

    def summary(name, values):
        return CheckpointSummary("c", name, (40,), values.mean(axis=0), values.std(axis=0), values, keys)

    other = summary("other", base)
    close, far = summary("close", base - 0.005 + jitter), summary("far", base - 0.02 + jitter)
    with_margin = compare(close, other, 0, "greater", margin=0.01)
    assert with_margin.significant and abs(with_margin.mean_a - close.mean[0]) < 1e-12
    assert with_margin.ci is not None and with_margin.ci[1] < 0  # the strategies' own difference: behind
    assert not compare(close, other, 0, "greater").significant
    assert not compare(far, other, 0, "greater", margin=0.01).significant


def test_an_episodes_suite_accepts_a_margin_but_not_than_at(tmp_path):
    text = suite_file(tmp_path).read_text()
    assert "[[finding]]" in text
    with_margin = text.replace("[[finding]]", "[[finding]]\nmargin = 0.01", 1)
    path = tmp_path / "margin.toml"
    path.write_text(with_margin)
    assert load_suite(path).findings[0].margin == 0.01
    path.write_text(text.replace("[[finding]]", "[[finding]]\nthan_at = 10", 1))
    with pytest.raises(SuiteError, match="'than_at' is only accepted"):
        load_suite(path)
