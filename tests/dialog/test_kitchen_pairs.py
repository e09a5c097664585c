"""The kitchen-pairs arm of a recipes suite (issue 52 item 3): a tiny real run over generated kitchens, the plan's
criterion on rows whose answer is known, and the suite's clear errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments.recipes.kitchen_pairs import analyse

TINY = """
name = "tiny-kitchen-pairs"
kind = "recipes"
axis = "demonstrations"
strategies = ["kitchen-pairs"]
checkpoints = [2]
seeds = [0]

[options]
recipes = ["serve-salad"]
kitchens = { generated = [9001, 9002], also = ["kitchen-2"] }
transfer_demos = 3
transfer_m = [2]
tested_in = 1
pairs_of_kitchens = 1
pair_executions = 1
"""


def test_a_tiny_suite_trains_in_each_kitchen_and_a_pair_tests_elsewhere_and_executes(tmp_path, monkeypatch):
    monkeypatch.setenv("TEACHBOT_CACHE", str(tmp_path / "cache"))
    suite = tmp_path / "tiny.toml"
    suite.write_text(TINY)
    assert main(["regress", "--suite", str(suite), "--results", str(tmp_path / "out"), "--no-progress",
                 "--workers", "2"]) == 0
    data = json.loads((tmp_path / "out" / "kitchen-pairs-serve-salad.json").read_text())
    singles = [r for r in data["rows"] if len(r["train"]) == 1]
    assert sorted(r["train"][0] for r in singles) == ["generated-9001", "generated-9002", "kitchen-2"]
    assert all(r["test"] != r["train"][0] and r["distance"] > 0 and 0 <= r["match"] <= 1 for r in singles)
    (paired,) = [r for r in data["rows"] if len(r["train"]) == 2]
    assert paired["test"] not in paired["train"]
    (executed,) = data["executions"]
    assert executed["m"] == 2 and isinstance(executed["success"], bool) and executed["steps"]
    report = (tmp_path / "out" / "report.md").read_text()
    assert "Transfer against the distance between kitchens" in report
    assert (tmp_path / "out" / "kitchen-pairs-serve-salad.png").stat().st_size > 0


def rows(match_of_distance, rng, trainers=12, tests=5):
    out = []
    for k in range(trainers):
        for t in range(tests):
            d = float(rng.uniform(0, 30))
            accuracy = {"a": match_of_distance(d, rng), "b": match_of_distance(d, rng)}
            out.append({"m": 5, "train": [f"k{k}"], "test": f"t{t}", "distance": d, "accuracy": accuracy,
                        "match": float(np.mean(list(accuracy.values())))})
    return out


def test_the_criterion_finds_a_fall_with_distance_and_none_in_noise():
    rng = np.random.default_rng(3)
    falling = analyse(rows(lambda d, r: float(np.clip(1 - d / 30 + r.normal(0, 0.05), 0, 1)), rng), 5, 500, 200, rng)
    assert falling["falls"] and falling["rho"] < -0.8 and falling["p"] < 0.01
    assert falling["means"][0] > falling["means"][-1] and all(lo <= m <= hi for lo, m, hi in
                                                             zip(falling["low"], falling["means"], falling["high"]))
    noise = analyse(rows(lambda d, r: float(r.uniform()), rng), 5, 500, 200, rng)
    assert not noise["falls"] and noise["p"] > 0.05


@pytest.mark.parametrize("kitchens, message", [
    ("{ generated = [9002, 9001] }", "'kitchens' as a table must be { generated = [FIRST, LAST] }"),
    ("{ generated = [9001, 9002], besides = [] }", "'kitchens' as a table must be"),
])
def test_a_bad_kitchen_range_is_one_clear_line(tmp_path, capsys, kitchens, message):
    suite = tmp_path / "tiny.toml"
    suite.write_text(TINY.replace('{ generated = [9001, 9002], also = ["kitchen-2"] }', kitchens))
    assert main(["regress", "--suite", str(suite), "--results", str(tmp_path / "out"), "--no-progress"]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and message in error


def test_the_draws_follow_the_kitchens_names_not_where_their_files_are():
    """A generated kitchen's file sits in the cache, which differs from machine to machine."""
    from types import SimpleNamespace

    from dialog.experiments.kitchens import label
    from dialog.experiments.recipes.kitchen_pairs import training_sets
    from dialog.experiments.recipes.suite import job_rng

    def drawn(folder: str) -> list:
        kitchens = [f"{folder}/generated-{s}.toml" for s in (1, 2, 3)] + ["kitchen-1", "kitchen-2"]
        study = SimpleNamespace(kitchens=kitchens, tested_in=2, pairs_of_kitchens=2)
        return [([label(k) for k in train], [label(k) for k in tests])
                for train, tests in training_sets(study, 0, job_rng)]

    assert drawn("/root/.cache/teachbot/kitchens/abc") == drawn("zz/elsewhere")
