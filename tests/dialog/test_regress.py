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


def test_a_new_baseline_keeps_the_stored_one_as_superseded(tmp_path, capsys):
    """Issue 24, item 1: a stored baseline is a record; --update-baseline keeps it, numbered, and says so."""
    suite = load_suite(write_suite(tmp_path))
    first = summarise([fake_result("passive", [0.5, 0.7, 0.8, 0.9], [1, 2, 3, 3], d) for d in range(3)], suite)
    second = summarise([fake_result("passive", [0.4, 0.6, 0.7, 0.8], [1, 2, 3, 3], d) for d in range(3)], suite)
    path = write_baseline(suite, first, tmp_path / "base.json")
    stored = path.read_bytes()
    write_baseline(suite, first, path)  # the same baseline again: nothing to keep
    assert not list(tmp_path.glob("base.json.superseded-*"))
    write_baseline(suite, second, path)
    assert (tmp_path / "base.json.superseded-1").read_bytes() == stored and path.read_bytes() != stored
    assert f"the earlier baseline is kept as {tmp_path / 'base.json.superseded-1'}" in capsys.readouterr().err
    write_baseline(suite, first, path)
    assert (tmp_path / "base.json.superseded-2").is_file()


@pytest.mark.parametrize("damage, fragment", [
    (b"\xff\xfe", "not UTF-8 text"), (b"[" * 100000, "not JSON"), (b"[1, 2, 3]", "no 'bands' table"),
    (b'{"bands": {"static": {"passive": {"2": {"mean": 0.5, "band": "wide"}}}}}', "bands.static.passive.2 is"),
    (b'{"bands": {"static": {"passive": {"2": {"mean": 0.5, "band": [0.6, 0.4]}}}}}', "low <= high"),
    (b'{"bands": {"static": {"passive": {"2": 7}}}}', "bands.static.passive.2 is 7"),
    (b'{"bands": {}, "data_seed": "zero"}', "'data_seed' is \"zero\""),
])
def test_a_damaged_baseline_is_one_line_naming_the_file(tmp_path, damage, fragment):
    """Issue 24, item 2: the suite results' reader checks every field (no traceback from a band that is a string)."""
    suite = load_suite(write_suite(tmp_path))
    summaries = summarise([fake_result("passive", [0.5, 0.7, 0.8, 0.9], [1, 2, 3, 3], d) for d in range(3)], suite)
    path = tmp_path / "base.json"
    path.write_bytes(damage)
    with pytest.raises(SuiteError, match="base.json: ") as refused:
        check_against_baseline(suite, summaries, path)
    assert fragment in str(refused.value) and "\n" not in str(refused.value)


def test_a_tiny_suite_runs_end_to_end(tmp_path, capsys):
    code = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "out"),
                 "--workers", "1", "--no-progress", "--json"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["suite"] == "tiny" and summary["episodes"] == 4 and summary["passed"]
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
