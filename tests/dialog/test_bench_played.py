"""scripts/bench_played.py: DT's decisions timed as a suite's episodes play them, checked against the reference."""

import json
from dataclasses import replace
from pathlib import Path

import pytest

from dialog.experiments.episodes import run_episode
from dialog.experiments.runner import episode_specs
from dialog.experiments.suite import load_suite
from learning.strategies import make_strategy
from tests.scripts import load_script


def _load():
    return load_script("bench_played")


def test_timing_and_reference_checks_leave_the_episode_unchanged(tmp_path):
    bench = _load()
    suite = replace(load_suite("smoke"), strategies=("dt-task",), datasets=1, seeds=(0,))
    plain_spec, = episode_specs(suite, tmp_path / "plain")
    timed_spec, = episode_specs(suite, tmp_path / "timed")
    run_episode(plain_spec)
    strategy = make_strategy("dt-task")
    log = bench.DecisionLog(strategy, reference_every=3)
    run_episode(timed_spec, strategy)
    assert Path(plain_spec.transcript).read_bytes() == Path(timed_spec.transcript).read_bytes()
    choices = sum(row["candidates"] > 1 for row in log.rows)  # the reference checks only real choices
    assert len(log.rows) == plain_spec.condition.turns and len(log.checks) == choices // 3 > 0
    assert all(row["cpu_ms"] > 0 and row["scene"] == 12 for row in log.rows)
    assert [row["n_train"] for row in log.rows] == sorted(row["n_train"] for row in log.rows)  # examples only grow
    assert log.rows[0]["cold"] and any(row["fsq_open"] for row in log.rows)


def test_the_json_line_summarises_every_condition(capsys):
    bench = _load()
    assert bench.main(bench._parse(["--suite", "smoke", "--datasets", "1", "--reference-every", "5", "--json"])) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    (row,) = report["conditions"]
    assert row["condition"] == "static" and row["decisions"] == 20
    assert 0 < row["choices"] <= 20 and row["reference_checks"] == row["choices"] // 5  # every fifth real choice
    assert row["cpu_ms"]["p50"] > 0 and row["cpu_ms"]["p95"] >= row["cpu_ms"]["p50"]
    assert 0 < row["fsq_open_share"] < 1 and row["speedup_cpu"] > 1
    # where the fast choice differs from the reference's, it is a near tie: expected utilities agree to < 1e-3
    # (docs/strategies.md, the what-if engines' approximation error)
    assert row["same_action"] > 0 and row["max_regret"] < 1e-3


def test_a_condition_the_suite_lacks_gets_one_message_naming_the_accepted_ones():
    bench = _load()
    with pytest.raises(SystemExit) as stopped:
        bench.main(bench._parse(["--suite", "smoke", "--condition", "nope"]))
    assert "accepted: static" in str(stopped.value)
