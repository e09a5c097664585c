"""Replication on new data (the data seed of suites, pools, episodes, baselines) and user weights (--weights)."""

import argparse
import functools
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments import pools
from dialog.experiments.baseline import (
    baseline_path,
    check_against_baseline,
    refuse_baseline_from_another_run,
    refuse_other_data_seed,
    write_baseline,
)
from dialog.experiments.episodes import run_episode
from dialog.experiments.runner import episode_specs
from dialog.experiments.suite import SuiteError, load_suite
from dialog.settings import EpisodeSettings
from dialog.user_weights import (
    UserWeights,
    named_weights,
    read_named_weights,
    read_user_weights,
    weights_from_header,
    weights_strategy,
)
from learning.decision.weights_file import DecisionWeights, save_weights
from learning.errors import DataFileError, SettingsError, TranscriptError

SMALL_PLAN = (("objects_per_scene", 8), ("pool_size", 12), ("test_size", 8))


def _suite_file(tmp_path, extra: str) -> str:
    path = tmp_path / "mini.toml"
    path.write_text(f'name = "mini"\nstrategies = ["passive"]\ncheckpoints = [2]\n{extra}\n'
                    '[[condition]]\nname = "c"\nbudget = 4\nturns = 4\nchange_every = 2\n')
    return str(path)


def test_a_suite_reads_its_data_seed_and_defaults_to_today_s_data(tmp_path):
    assert load_suite("smoke").data_seed == 0
    assert load_suite(_suite_file(tmp_path, "data_seed = 7")).data_seed == 7
    for bad in ("data_seed = -1", 'data_seed = "one"', "data_seed = 1.5"):
        with pytest.raises(SuiteError, match="data_seed"):
            load_suite(_suite_file(tmp_path, bad))
    with pytest.raises(SuiteError, match="'data_seed' is not accepted in a suite of kind 'recipes'"):
        load_suite(_suite_file(tmp_path, 'kind = "recipes"\ndata_seed = 1'))


def test_the_command_line_data_seed_overrides_the_suite_s_and_reaches_every_episode(tmp_path):
    suite = load_suite("smoke").with_overrides(data_seed=3)
    assert suite.data_seed == 3
    specs = episode_specs(suite, tmp_path)
    assert specs and {spec.data_seed for spec in specs} == {3}
    assert pickle.loads(pickle.dumps(specs[0])).data_seed == 3  # specs travel to workers and Ray pickled
    with pytest.raises(SuiteError, match="data seed"):
        load_suite("smoke").with_overrides(data_seed=-2)
    with pytest.raises(SuiteError, match="kind 'recipes', which renders no data sets"):
        load_suite("recipes").with_overrides(data_seed=1)


def test_pools_from_another_data_seed_are_other_data_and_cached_under_their_seed(tmp_path, monkeypatch):
    monkeypatch.setattr(pools, "load_datasets", functools.partial(pools.load_datasets, cache=tmp_path))
    monkeypatch.setattr(pools, "_loaded", {})
    today = pools.load_pools("pack-lunchbox", "kitchen-1", 1, SMALL_PLAN)
    fresh = pools.load_pools("pack-lunchbox", "kitchen-1", 1, SMALL_PLAN, data_seed=5)
    assert not np.array_equal(today.test.X, fresh.test.X)
    assert len(pools._loaded) == 2  # the data seed is part of the in-memory key
    cached = sorted(p.name for p in (tmp_path / "datasets").glob("*.npz"))
    assert any("-seed0-" in name for name in cached) and any("-seed5-" in name for name in cached)
    monkeypatch.setattr(pools, "_loaded", {})
    again = pools.load_pools("pack-lunchbox", "kitchen-1", 1, SMALL_PLAN, data_seed=5)
    assert np.array_equal(again.test.X, fresh.test.X)
    with pytest.raises(ValueError, match="data seed"):
        pools.load_pools("pack-lunchbox", "kitchen-1", 1, SMALL_PLAN, data_seed=-1)


# -- user weights ---------------------------------------------------------------------------------------------

TINY = """name = "tiny-replication"
strategies = ["passive"]
datasets = 1
checkpoints = [1, 2, 3]
[dataset]
pool_size = 24
test_size = 24
[[condition]]
name = "static"
budget = 3
turns = 4
change_every = 2
"""


def _weights_file(tmp_path, name="mine.toml", **values) -> str:
    values = values or {"classifier_discriminability": 1.0, "budget_consumption": -0.4}
    return str(save_weights(tmp_path / name, DecisionWeights(tuple(values), list(values.values()),
                                                             {"method": "test"})))


def test_a_weights_file_reads_as_the_features_it_names(tmp_path):
    weights = read_user_weights(_weights_file(tmp_path))
    assert weights.values == (("classifier_discriminability", 1.0), ("budget_consumption", -0.4))
    strategy = weights.strategy("mine")
    assert strategy.name == "mine"
    assert list(strategy.weights) == [1.0, 0.0, 0.0, 0.0, -0.4, 0.0, 0.0]  # features left out weigh 0
    assert pickle.loads(pickle.dumps(weights)) == weights


def test_bad_weights_files_are_one_clear_message(tmp_path):
    with pytest.raises(DataFileError, match="no weights file there"):
        read_user_weights(tmp_path / "missing.toml")
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("[weights]\nclassifier_discriminability = 1.0\nsparkle = 2.0\n")
    with pytest.raises(DataFileError, match="unknown decision feature 'sparkle'"):
        read_user_weights(unknown)
    broken = tmp_path / "broken.toml"
    broken.write_text("[weights]\nclassifier_discriminability = 'high'\n")
    with pytest.raises(DataFileError, match=str(broken)):
        read_user_weights(broken)


def test_named_weights_refuse_built_in_names_and_malformed_pairs(tmp_path):
    assert named_weights("mine=w.toml") == ("mine", Path("w.toml"))
    with pytest.raises(argparse.ArgumentTypeError, match="built-in strategy.*passive, active"):
        named_weights("dt-task=w.toml")
    for bad in ("mine", "=w.toml", "mine=", "my/name=w.toml"):
        with pytest.raises(argparse.ArgumentTypeError):
            named_weights(bad)
    file = _weights_file(tmp_path)
    with pytest.raises(SettingsError, match="given twice"):
        read_named_weights([("mine", file), ("mine", file)])


def test_weights_stand_in_only_for_a_dt_strategy(tmp_path):
    file = Path(_weights_file(tmp_path))
    assert weights_strategy("active", None) == ("active", None)
    name, weights = weights_strategy("dt-task", file)
    assert name == "dt" and weights.file == str(file.resolve())
    with pytest.raises(SettingsError, match="--strategy passive does not use weights"):
        weights_strategy("passive", file)


def test_a_recorded_weights_header_is_checked(tmp_path):
    weights = read_user_weights(_weights_file(tmp_path))
    assert weights_from_header(weights.record(), "t.jsonl") == weights
    assert weights_from_header(None, "t.jsonl") is None
    for bad in ({"file": "w.toml"}, {"file": "w.toml", "values": {"sparkle": 1.0}},
                {"file": "", "values": {"budget_consumption": 1.0}}, [1, 2]):
        with pytest.raises(TranscriptError, match="t.jsonl: line 1: the session header's 'weights'"):
            weights_from_header(bad, "t.jsonl")
        with pytest.raises(SettingsError, match="weights must be a table"):
            EpisodeSettings(strategy="dt", weights=bad)
    settings = EpisodeSettings(strategy="dt", weights=weights.record())
    assert list(settings.build_strategy().weights) == [1.0, 0.0, 0.0, 0.0, -0.4, 0.0, 0.0]


def test_with_weights_adds_named_dt_strategies_to_episodes_suites_only(tmp_path):
    weights = {"mine": read_user_weights(_weights_file(tmp_path))}
    suite = load_suite("smoke").with_weights(weights)
    assert suite.strategies[-1] == "mine" and suite.weights == weights
    specs = episode_specs(suite, tmp_path)
    assert {s.weights is None for s in specs if s.strategy != "mine"} == {True}
    assert all(s.weights == weights["mine"] for s in specs if s.strategy == "mine")
    with pytest.raises(SuiteError, match="already a strategy"):
        suite.with_weights(weights)
    with pytest.raises(SuiteError, match="of kind 'feature-selection'"):
        load_suite("ch5").with_weights(weights)


def test_an_episode_with_user_weights_is_the_dt_preset_with_the_same_weights(tmp_path):
    preset = {"classifier_discriminability": 1.0, "class_distribution_uniformity": 0.05}  # dt-iros's weights
    suite = load_suite(_suite_file_text(tmp_path, TINY)).with_overrides(strategies=["dt-iros"])
    suite = suite.with_weights({"mine": UserWeights("w.toml", tuple(preset.items()))})
    specs = episode_specs(suite, tmp_path)
    ours, theirs = (run_episode(next(s for s in specs if s.strategy == name)) for name in ("mine", "dt-iros"))
    assert ours["series"] == theirs["series"] and ours["label"].startswith("mine/")
    header = json.loads(Path(specs[-1].transcript).read_text().splitlines()[0])["session"]
    assert header["strategy"] == "mine"


def _suite_file_text(tmp_path, text: str) -> str:
    path = tmp_path / "tiny.toml"
    path.write_text(text)
    return str(path)


def test_baselines_record_their_data_seed_and_check_refuses_another(tmp_path):
    suite = load_suite(_suite_file_text(tmp_path, TINY))
    path = write_baseline(suite, [], tmp_path / "b.json")
    assert json.loads(path.read_text())["data_seed"] == 0
    refuse_other_data_seed(suite, path)  # same data: fine
    other = suite.with_overrides(data_seed=4)
    with pytest.raises(SuiteError, match="data seed 0, this run uses data seed 4.*--data-seed 0"):
        refuse_other_data_seed(other, path)
    assert check_against_baseline(other, [], path) == [
        f"baseline {path} was made on data seed 0, this run on data seed 4: not comparable"]
    legacy = tmp_path / "legacy.json"
    legacy.write_text(json.dumps({"bands": {}}))  # baselines written before data seeds: data seed 0
    refuse_other_data_seed(suite, legacy)
    with pytest.raises(SuiteError):
        refuse_other_data_seed(other, legacy)


def test_regress_check_on_another_data_seed_is_refused_before_anything_runs(tmp_path, capsys):
    code = main(["regress", "--suite", "smoke", "--data-seed", "1", "--check", "--results", str(tmp_path / "out"),
                 "--no-progress"])
    assert code == 2
    err = capsys.readouterr().err
    assert "teachbot regress: --check: the baseline" in err and "data seed 0" in err and "data seed 1" in err
    assert not (tmp_path / "out" / "report.md").exists()


@pytest.mark.parametrize("extra", [["--weights", "mine=WEIGHTS"], ["--data-seed", "1"]])
def test_regress_update_baseline_with_a_run_not_the_suite_s_own_is_refused_before_anything_runs(
        tmp_path, capsys, extra):
    stored = baseline_path(load_suite("smoke")).read_bytes()
    extra = [value.replace("WEIGHTS", _weights_file(tmp_path)) for value in extra]
    code = main(["regress", "--suite", "smoke", "--update-baseline", *extra, "--results", str(tmp_path / "out"),
                 "--no-progress"])
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("teachbot regress: --update-baseline stores the suite's own run")
    assert ("--weights strategies (mine)" in err) if extra[0] == "--weights" else ("this run uses data seed 1" in err)
    assert not (tmp_path / "out").exists()
    assert baseline_path(load_suite("smoke")).read_bytes() == stored


def test_update_baseline_accepts_the_suite_s_own_data_seed_and_refuses_others(tmp_path):
    suite = load_suite(_suite_file_text(tmp_path, "data_seed = 3\n" + TINY))
    refuse_baseline_from_another_run(suite, suite)  # the suite's own run: fine
    refuse_baseline_from_another_run(suite.with_overrides(data_seed=3), suite)  # --data-seed 3 is its own
    with pytest.raises(SettingsError, match="made on the data sets of data seed 3; this run uses data seed 0"):
        refuse_baseline_from_another_run(suite.with_overrides(data_seed=0), suite)
    weighted = suite.with_weights(read_named_weights([("mine", _weights_file(tmp_path))]))
    with pytest.raises(SettingsError, match=r"adds --weights strategies \(mine\)"):
        refuse_baseline_from_another_run(weighted, suite)
    for overrides, option in (({"seeds": [7]}, "--seeds"), ({"budget": 5.0}, "--budget"),
                              ({"datasets": 2}, "--datasets"), ({"strategies": ["active"]}, "--strategies")):
        with pytest.raises(SettingsError, match=f"changes the suite with {option}"):
            refuse_baseline_from_another_run(suite.with_overrides(**overrides), suite)


def test_regress_weights_errors_are_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as stopped:
        main(["regress", "--suite", "smoke", "--weights", "active=x.toml"])
    assert stopped.value.code == 2 and "'active' is a built-in strategy" in capsys.readouterr().err
    assert main(["regress", "--suite", "smoke", "--weights", f"mine={tmp_path / 'x.toml'}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no weights file there" in err and "Traceback" not in err


def test_regress_with_weights_and_a_data_seed_labels_and_states_both(tmp_path, capsys):
    file = _weights_file(tmp_path)
    code = main(["regress", "--suite", _suite_file_text(tmp_path, TINY), "--weights", f"mine={file}",
                 "--data-seed", "2", "--results", str(tmp_path / "out"), "--workers", "2", "--no-progress",
                 "--json"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["episodes"] == 2 and summary["data_seed"] == 2
    report = (tmp_path / "out" / "report.md").read_text()
    assert "data sets rendered from data seed 2 (fresh data: a replication)" in report
    assert f"strategy `mine`: DT with the weights in {Path(file).resolve()}" in report
    assert "| mine |" in report
    rows = (tmp_path / "out" / "episodes.csv").read_text().splitlines()
    assert [row.split(",")[1] for row in rows[1:]] == ["passive", "mine"]
