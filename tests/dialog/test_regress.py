"""Regression suites: loading, checkpoint analysis, findings, baselines, and one tiny real run."""

import json

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments.analysis import checkpoint_values, evaluate_findings, summarise
from dialog.experiments.baseline import check_against_baseline, write_baseline
from dialog.experiments.suite import SuiteError, load_suite

SUITE = """
name = "tiny"
description = "test suite"
strategies = ["passive", "active"]
datasets = 2
checkpoints = [1, 2, 3]
[dataset]
pool_size = 24
test_size = 24
[costs]
label = 1
demo = 1
feature = 1
none = 0
[[condition]]
name = "static"
budget = 3
turns = 4
change_every = 2
[[finding]]
id = "f1"
text = "passive beats active"
condition = "static"
at = 3
better = "passive"
than = ["active"]
"""


def write_suite(tmp_path, text=SUITE):
    path = tmp_path / "tiny.toml"
    path.write_text(text)
    return path


def fake_result(strategy, accuracies, questions, dataset=0):
    n = len(accuracies)
    return {"spec": {"condition": {"name": "static"}, "strategy": strategy, "dataset": dataset, "seed": 0},
            "series": {"turn": list(range(1, n + 1)), "accuracy": accuracies, "questions": questions,
                       "label": questions, "demo": [0] * n, "feature": [0] * n, "spent": questions},
            "accuracy": accuracies[-1], "seconds": 0.1}


def test_suite_errors_name_the_problem(tmp_path):
    with pytest.raises(SuiteError, match="unknown suite 'nope'; available: .*smoke"):
        load_suite("nope")
    with pytest.raises(SuiteError, match="unknown strategies \\['clever'\\]"):
        load_suite(write_suite(tmp_path, SUITE.replace('"active"]', '"clever"]')), ["passive", "active"])
    with pytest.raises(SuiteError, match="missing field 'budget'"):
        load_suite(write_suite(tmp_path, SUITE.replace("budget = 3\n", "")))
    with pytest.raises(SuiteError, match="not in the suite's strategies"):
        load_suite(write_suite(tmp_path, SUITE.replace('than = ["active"]', 'than = ["random"]')))


def test_checkpoints_use_the_first_turn_with_enough_questions_else_the_final_accuracy(tmp_path):
    suite = load_suite(write_suite(tmp_path))
    result = fake_result("active", [0.3, 0.5, 0.6, 0.7], [1, 1, 2, 2])
    assert checkpoint_values(result, suite) == pytest.approx([0.3, 0.6, 0.7])


def test_findings_and_baseline_bands(tmp_path):
    suite = load_suite(write_suite(tmp_path))
    results = [fake_result("passive", [0.5, 0.7, 0.8, 0.9], [1, 2, 3, 3], d) for d in range(5)]
    results += [fake_result("active", [0.3, 0.4, 0.45, 0.5], [1, 2, 3, 3], d) for d in range(5)]
    summaries = summarise(results, suite)
    (finding,) = evaluate_findings(summaries, suite)
    assert finding.holds and finding.comparisons[0].p < 0.01
    path = write_baseline(suite, summaries, tmp_path / "base.json")
    assert check_against_baseline(suite, summaries, path) == []
    worse = summarise([fake_result("passive", [0.5, 0.5, 0.5, 0.5], [1, 2, 3, 3])] + results[5:], suite)
    failures = check_against_baseline(suite, worse, path)
    assert failures and "passive/static after 2 questions: accuracy 0.500 is below its band" in failures[0]
    assert "no stored baseline" in check_against_baseline(suite, summaries, tmp_path / "missing.json")[0]


def test_a_tiny_suite_runs_end_to_end(tmp_path, capsys):
    code = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "out"),
                 "--workers", "1", "--no-progress", "--json"])
    assert code == 0
    out = capsys.readouterr().out.strip().splitlines()
    summary = json.loads(out[-1])
    assert summary["suite"] == "tiny" and summary["episodes"] == 4 and summary["passed"]
    assert summary["episodes_per_second"] > 0 and 0 < summary["cpu_use"] <= 1.0
    assert any(line.strip().startswith("4 episodes in ") and "episodes per second; CPU use" in line for line in out)
    report = (tmp_path / "out" / "report.md").read_text()
    assert "f1: passive beats active" in report and "curves-static.png" in report
    assert (tmp_path / "out" / "curves-static.png").stat().st_size > 1000
    rows = (tmp_path / "out" / "episodes.csv").read_text().splitlines()
    assert len(rows) == 5 and rows[0].startswith("condition,strategy")
    first = np.loadtxt(tmp_path / "out" / "episodes" / "static" / "passive-d0-s0.csv", delimiter=",", skiprows=1)
    assert first.shape == (4, 7) and first[-1, 6] <= 3


def test_the_same_suite_runs_on_a_local_ray_instance(tmp_path, capsys):
    ray = pytest.importorskip("ray", reason="the optional Ray extra is not installed")
    try:
        code = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "ray"),
                     "--ray", "local", "--no-progress", "--json"])
    finally:
        ray.shutdown()
    assert code == 0
    local = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "local"),
                  "--workers", "1", "--no-progress", "--json"])
    assert local == 0
    on_ray = (tmp_path / "ray" / "episodes.csv").read_text().splitlines()
    here = (tmp_path / "local" / "episodes.csv").read_text().splitlines()
    def without_timing(rows):
        return [",".join(row.split(",")[:10]) for row in rows]

    assert without_timing(on_ray) == without_timing(here)


def test_sweep_use_is_the_runs_cpu_time_over_wall_time_and_cores():
    from dialog.experiments.kinds import SweepUse

    sweep = SweepUse(runs=80, seconds=10.0, cpu_seconds=17.0, cores=2)
    assert sweep.runs_per_second == 8.0 and sweep.cpu_use == pytest.approx(0.85)
    assert sweep.line() == "80 episodes in 10.0 s: 8.00 episodes per second; CPU use 85% of 2 cores"
    assert SweepUse(0, 0.0, 0.0, 2).cpu_use == 0.0


def test_scripted_feature_answers_follow_the_user_model():
    from dialog.experiments.features.study import UserModel, hfr_answer, hfs_answer

    names = ("colour.red", "size.height", "location.x", "arm.joint1", "weight")
    relevant = {"colour.red", "size.height", "weight"}
    perfect = UserModel(keep_relevant=1.0, add_irrelevant=0.0, ignore_robot=1.0, ignore_irrelevant_object=1.0,
                        ignore_relevant=0.0)
    rng = np.random.default_rng(0)
    assert hfs_answer(names, relevant, perfect, rng).tolist() == [0, 1, 4]
    assert hfr_answer(names, relevant, perfect, rng).tolist() == [0, 1, 4]
    lax = UserModel(ignore_robot=0.0, ignore_irrelevant_object=0.0, ignore_relevant=0.0)
    assert hfr_answer(names, relevant, lax, rng).tolist() == [0, 1, 2, 3, 4]  # ignoring nothing keeps all


def test_stratified_samples_are_balanced_and_disjoint():
    from dialog.experiments.features.study import srs

    concepts = np.array(["a", "b"] * 20, dtype=object)
    rng = np.random.default_rng(1)
    first = srs(concepts, 10, rng)
    second = srs(concepts, 10, rng, exclude=first)
    assert sorted(concepts[first].tolist()) == ["a"] * 5 + ["b"] * 5
    assert not set(first) & set(second)
    with pytest.raises(ValueError, match="free rows of 'a'"):
        srs(concepts, 50, rng)


def test_a_strategy_subset_says_which_findings_it_skips(tmp_path, capsys):
    code = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "out"),
                 "--workers", "1", "--no-progress", "--strategies", "passive"])
    assert code == 0
    out = capsys.readouterr().out
    assert "f1: skipped: needs active, not among the strategies run (passive)" in out
    report = (tmp_path / "out" / "report.md").read_text()
    assert "- f1: passive beats active: skipped, needs active, not among the strategies run (passive)" in report
