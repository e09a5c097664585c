"""Regression suites: loading, checkpoint analysis, findings, baselines, and one tiny real run."""

import json

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments.analysis import checkpoint_values, evaluate_findings, summarise
from dialog.experiments.baseline import check_against_baseline, write_baseline
from dialog.experiments.suite import SuiteError, load_suite
from learning.errors import SettingsError

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
    paired = finding.comparisons[0]  # the same 5 data sets for both: paired, 5 pairs, all favour passive
    assert finding.holds and paired.n == 5 and paired.p == pytest.approx(1 / 32) and paired.effect == 1.0
    path = write_baseline(suite, summaries, tmp_path / "base.json")
    passed = check_against_baseline(suite, summaries, path)
    assert passed == [] and passed.verdict() == "baseline check: passed (6 of 6 within bands)"
    worse = summarise([fake_result("passive", [0.5, 0.5, 0.5, 0.5], [1, 2, 3, 3])] + results[5:], suite)
    failures = check_against_baseline(suite, worse, path)
    assert failures and "passive/static after 2 questions: accuracy 0.500 is below its band" in failures[0]
    within = 6 - len(failures)
    assert failures.verdict() == f"baseline check: FAILED ({len(failures)} problems; {within} of 6 bands within)"
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


def test_check_prints_its_verdict_without_json(tmp_path, capsys, monkeypatch):
    """Issue 23 case 9: --check used to say nothing when it passed unless --json was given."""
    monkeypatch.setattr("dialog.experiments.baseline.BASELINE_DIR", tmp_path / "baselines")
    suite = str(write_suite(tmp_path))
    common = ["regress", "--suite", suite, "--results", str(tmp_path / "out"), "--workers", "1", "--no-progress"]
    assert main(common + ["--update-baseline"]) == 0
    capsys.readouterr()
    assert main(common + ["--check"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "baseline check: passed (6 of 6 within bands)"


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


def test_the_pack_lunchbox_experiments_run_on_55_object_scenes(tmp_path, capsys):
    """Issue 26 item 1: the thesis's pack-lunchbox scenes hold 55 objects (§6.5); the suites drew 12."""
    from dialog.transcripts.jsonl import read_session
    assert {c.objects_per_scene for c in load_suite("ch6-static").conditions} == {55}
    assert {c.objects_per_scene for c in load_suite("ch7-pack-lunchbox").conditions} == {55}
    assert {c.objects_per_scene for c in load_suite("smoke").conditions} == {None}  # the task's 12
    out = tmp_path / "out"
    assert main(["regress", "--suite", "ch7-pack-lunchbox", "--strategies", "passive", "--seeds", "0",
                 "--datasets", "1", "--results", str(out), "--workers", "1", "--no-progress"]) == 0
    (transcript,) = (out / "transcripts").rglob("*.jsonl")
    records = read_session(transcript)[1]
    assert {record["scene_check"]["objects"] for record in records} == {55}
    assert "a new scene every 10 turns, 55 objects a scene" in (out / "report.md").read_text()


def test_a_scene_size_beyond_the_task_is_refused(tmp_path):
    from dialog.experiments.pools import PoolEnvironment, load_pools
    pools = load_pools("pack-lunchbox", "kitchen-1", 1)
    with pytest.raises(SettingsError, match="objects_per_scene 56 is not accepted .* 1 to 55 objects"):
        PoolEnvironment(pools.train[0], pools.test, pools.task, 1, objects_per_scene=56)
    suite = load_suite(write_suite(tmp_path, "objects_per_scene = 20\n" + SUITE))
    assert {c.objects_per_scene for c in suite.conditions} == {20}


def test_a_suite_on_several_data_seeds_reports_each_and_pooled(tmp_path, capsys):
    """Issue 26 item 5: regress --data-seeds runs the suite on each rendered data set and pools the findings."""
    suite = write_suite(tmp_path)
    out = tmp_path / "out"
    assert main(["regress", "--suite", str(suite), "--data-seeds", "0", "1", "--results", str(out), "--workers", "1",
                 "--no-progress", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["data_seeds"] == [0, 1] and summary["episodes"] == 8 and set(summary["pooled"]) == {"f1"}
    assert (out / "data-seed-0" / "report.md").exists() and (out / "data-seed-1" / "report.md").exists()
    text = (out / "replication.md").read_text()
    assert "| finding | data seed 0 | data seed 1 | pooled | pooled pairs |" in text
    assert "teachbot regress --suite" in text and "--data-seeds 0 1" in text
    assert "(2 clusters)" in text  # the pooled interval resamples the two data seeds
    assert "none (1 cluster)" in (out / "data-seed-0" / "report.md").read_text()  # one data seed: no interval
    assert "Quiet turns with budget left" in text.split("pooled over the data seeds")[1]
    assert main(["regress", "--suite", str(suite), "--data-seeds", "0", "0", "--results", str(out)]) == 2
    assert "each data seed once" in capsys.readouterr().err
    assert main(["regress", "--suite", str(suite), "--data-seeds", "0", "--check", "--results", str(out)]) == 2


def test_render_only_prepares_every_data_seed_and_plays_nothing(tmp_path, capsys, monkeypatch):
    """Before a long run (a pre-registered one): --render-only loads (renders once) each data seed's data sets,
    in the suite's plan, and neither plays an episode nor writes a results folder."""
    loaded = []
    monkeypatch.setattr("dialog.experiments.pools.load_pools",
                        lambda task, kitchen, datasets, plan, progress=None, data_seed=0:
                        loaded.append((task, kitchen, datasets, data_seed)))
    suite = write_suite(tmp_path)
    out = tmp_path / "out"
    assert main(["regress", "--suite", str(suite), "--data-seeds", "3", "4", "--results", str(out), "--render-only",
                 "--no-progress", "--json"]) == 0
    assert [seed for *_, seed in loaded] == [3, 4] and not out.exists()
    lines = capsys.readouterr().out.strip().splitlines()
    assert "data seed 3) are ready" in lines[0] and json.loads(lines[-1])["data_seeds"] == [3, 4]
    assert main(["regress", "--suite", str(suite), "--render-only", "--check"]) == 2
    assert "--render-only plays no episode" in capsys.readouterr().err


def test_data_seeds_share_one_pool_and_give_the_files_of_a_run_in_one_process(tmp_path, capsys, monkeypatch):
    """Issue 54 item 3: one pool serves every data seed (the next one's episodes start before the last report
    is written); every transcript and the pooled numbers are those of the same run played in this process."""
    from dialog.experiments import runner

    pools = []
    monkeypatch.setattr(runner.EpisodePool, "__enter__", lambda self: pools.append(self) or self)
    suite = write_suite(tmp_path)
    outs = {workers: tmp_path / f"out-{workers}" for workers in ("1", "2")}
    for workers, out in outs.items():
        assert main(["regress", "--suite", str(suite), "--data-seeds", "0", "1", "2", "--results", str(out),
                     "--workers", workers, "--no-progress", "--json"]) == 0
    assert len(pools) == 1 and pools[0].workers == 2 and not pools[0]._futures  # one pool, every episode collected
    alone, shared = (sorted(p.relative_to(out) for p in out.rglob("*.jsonl")) for out in outs.values())
    assert alone == shared and len(alone) == 12
    for path in alone:
        assert (outs["1"] / path).read_bytes() == (outs["2"] / path).read_bytes()

    def numbers(out):
        summary = json.loads((out / "replication.json").read_text())
        return {key: value for key, value in summary.items() if key not in ("seconds", "command")}

    assert numbers(outs["1"]) == numbers(outs["2"])
