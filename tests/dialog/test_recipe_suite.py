"""The recipes kind of ``teachbot regress``: a tiny real suite end to end, baselines, findings, broken files."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from dialog.cli import main
from dialog.experiments import baseline
from dialog.experiments.recipes.suite import evaluate_recipe_findings, load_study, summarise_study
from dialog.experiments.suite import SuiteError, load_suite
from tests.scripts import load_script

TINY = """
name = "tiny-recipes"
description = "a tiny recipes suite"
kind = "recipes"
axis = "demonstrations"
strategies = ["cross-validation", "most-varied", "least-varied", "situated", "elsewhere", "execution"]
checkpoints = [1, 3]
seeds = [0]

[options]
recipes = ["serve-salad"]
kitchens = ["kitchen-1", "kitchen-2"]
demos = 4
cv_repeats = 3
transfer_demos = 3
transfer_m = [2]
transfer_repeats = 2
execution_trials = 1

[[finding]]
id = "rises"
text = "accuracy after 3 demonstrations beats accuracy after 1"
condition = "serve-salad"
better = "cross-validation"
at = 3
than = ["cross-validation"]
than_at = 1

[[finding]]
id = "no-transfer"
text = "models trained with the situated kitchen beat models from elsewhere"
condition = "serve-salad"
better = "situated"
at = 2
than = ["elsewhere"]
"""


def write(tmp_path: Path, text: str = TINY) -> Path:
    path = tmp_path / "tiny-recipes.toml"
    path.write_text(text)
    return path


def regress(capsys, *argv: str) -> tuple[int, dict, str]:
    code = main(["regress", *argv, "--no-progress", "--json"])
    captured = capsys.readouterr()
    return code, json.loads(captured.out.strip().splitlines()[-1]), captured.out


def test_a_tiny_recipes_suite_runs_end_to_end_and_checks_against_its_baseline(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(baseline, "BASELINE_DIR", tmp_path / "baselines")
    suite = str(write(tmp_path))
    code, summary, out = regress(capsys, "--suite", suite, "--results", str(tmp_path / "a"), "--workers", "2",
                                 "--update-baseline")
    assert code == 0 and set(summary) == {"suite", "episodes", "seconds", "passed", "failures"}
    # 2 kitchens x (cv 2 m x 3 repeats + 6 pairs + 1 execution) + transfer 3 training sets x 2 tests x 2 repeats
    assert summary["suite"] == "tiny-recipes" and summary["episodes"] == 2 * (6 + 6 + 1) + 12
    assert "rises: holds" in out and "no-transfer: holds" in out
    report = (tmp_path / "a" / "report.md").read_text()
    assert "## The thesis's chapter-4 findings, tested here" in report
    assert "| no-transfer: models trained with the situated kitchen" in report and "p (one-tailed)" in report
    for figure in ("overview-serve-salad.png", "cv-serve-salad.png", "transfer-serve-salad.png"):
        assert (tmp_path / "a" / figure).stat().st_size > 5000 and figure in report
    rows = list(csv.DictReader(open(tmp_path / "a" / "runs.csv")))
    assert {row["experiment"] for row in rows} == {"cv", "pairs", "transfer"}
    assert len(rows) == 5 * (2 * (6 + 6) + 12)  # one row per parameter of serve-salad
    steps = list(csv.DictReader(open(tmp_path / "a" / "execution.csv")))
    assert len(steps) == 2 * 2 and {s["step"] for s in steps} == {"pick-place <bowl, cupboard, counter>",
                                                                   "pick-place <salad-dressing, fridge, counter>"}
    stored = json.loads((tmp_path / "baselines" / "tiny-recipes.json").read_text())
    assert set(stored["bands"]["serve-salad"]) == {"cross-validation", "most-varied", "least-varied", "situated",
                                                   "elsewhere", "execution"}
    assert set(stored["bands"]["serve-salad"]["cross-validation"]) == {"1", "3"}

    # one worker gives the very same trials: inside every band but one made impossible, which --check names
    path = tmp_path / "baselines" / "tiny-recipes.json"
    stored["bands"]["serve-salad"]["situated"]["2"] = {"mean": 1.5, "band": [1.4, 1.6]}
    path.write_text(json.dumps(stored))
    code, summary, _ = regress(capsys, "--suite", suite, "--results", str(tmp_path / "b"), "--workers", "1",
                               "--check", "--strategies", "cross-validation", "most-varied", "least-varied",
                               "situated", "elsewhere")
    assert code == 1 and not summary["passed"] and summary["episodes"] == 2 * (6 + 6) + 12
    (failure,) = summary["failures"]
    assert failure.startswith("situated/serve-salad after 2 demonstrations: accuracy ") and \
        "is below its band [1.400, 1.600] (baseline 1.500)" in failure
    assert (tmp_path / "b" / "runs.csv").read_text() == (tmp_path / "a" / "runs.csv").read_text()
    assert "Execution with the arm" in report
    assert "Execution with the arm" not in (tmp_path / "b" / "report.md").read_text()


@pytest.mark.parametrize("change, message", [
    (('"execution"]', '"execution", "guessing"]'), "unknown arms ['guessing'] in 'strategies'"),
    (("demos = 4", "demos = 4\nrepeats = 3"), "unknown option 'repeats'; accepted: recipes, kitchens"),
    (("checkpoints = [1, 3]", "checkpoints = [1, 4]"), "checkpoints (m) must lie in 1..3 with demos = 4"),
    (('recipes = ["serve-salad"]', 'recipes = ["serve-soup"]'), "unknown built-in recipe 'serve-soup'"),
    (('kitchens = ["kitchen-1", "kitchen-2"]', 'kitchens = ["kitchen-1"]'), "needs at least two kitchens"),
    (("transfer_m = [2]", "transfer_m = [3]"), "'transfer_m' must lie in 1..2 with transfer_demos = 3"),
    (("cv_repeats = 3", "cv_repeats = 0"), "'cv_repeats' must be a whole number >= 1, got 0"),
    (('condition = "serve-salad"\nbetter = "situated"', 'condition = "serve-pasta"\nbetter = "situated"'),
     "condition 'serve-pasta' must be one of the suite's recipes ['serve-salad']"),
    (("at = 2\nthan = [\"elsewhere\"]", "at = 3\nthan = [\"elsewhere\"]"),
     "arm 'situated' is measured at m = [2], not 3"),
    (("than_at = 1", "than_at = 1\nmargin = -0.1"), "'margin' must be >= 0, got -0.1"),
])
def test_a_broken_recipes_suite_gets_one_clear_line(tmp_path, capsys, change, message):
    old, new = change
    assert old in TINY
    path = write(tmp_path, TINY.replace(old, new, 1))
    assert main(["regress", "--suite", str(path), "--results", str(tmp_path / "out"), "--no-progress"]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and message in error and str(path) in error


def test_cross_checkpoint_fields_are_refused_outside_recipes_suites(tmp_path):
    text = TINY.replace('kind = "recipes"', 'kind = "feature-selection"')
    with pytest.raises(SuiteError, match="'than_at' is only accepted in a suite of kind 'recipes'"):
        load_suite(write(tmp_path, text))


def fake_results(cv: dict[int, list[float]], situated: list[float], elsewhere: list[float]) -> dict:
    """Job results as ``run_recipe_suite`` returns them, with one parameter whose accuracy is given."""
    cv_runs = [{"m": m, "repeat": i, "accuracy": {"bowl": v}} for m, values in cv.items() for i, v in enumerate(values)]
    transfer = [{"m": 2, "train": ["kitchen-1"], "test": "kitchen-1", "situated": True, "repeat": i,
                 "accuracy": {"bowl": v}} for i, v in enumerate(situated)]
    transfer += [{"m": 2, "train": ["kitchen-2"], "test": "kitchen-1", "situated": False, "repeat": i,
                  "accuracy": {"bowl": v}} for i, v in enumerate(elsewhere)]
    return {"collect": [], "pairs": [], "cv": [{"seed": 0, "recipe": "serve-salad", "kitchen": "kitchen-1",
                                                "runs": cv_runs}],
            "transfer": [{"seed": 0, "recipe": "serve-salad", "kitchen": "kitchen-1", "m": 2, "runs": transfer}]}


def test_findings_compare_across_checkpoints_and_a_margin_makes_a_non_inferiority_test(tmp_path):
    text = TINY.replace("than_at = 1", "than_at = 1\nmargin = 0.0")
    suite = load_suite(write(tmp_path, text))
    study = load_study(suite)
    rising = fake_results({1: [0.2, 0.3, 0.25, 0.35, 0.3], 3: [0.8, 0.9, 0.85, 0.95, 0.9]}, [0.9] * 5, [0.1] * 5)
    summaries = summarise_study(rising, study)
    cv = next(s for s in summaries if s.strategy == "cross-validation")
    assert cv.checkpoints == (1, 3) and cv.mean == pytest.approx([0.28, 0.88])
    rises, no_transfer = evaluate_recipe_findings(summaries, suite)
    assert rises.holds and rises.comparisons[0].p < 0.01 and rises.comparisons[0].b == "cross-validation m=1"
    assert no_transfer.holds
    flat = summarise_study(fake_results({1: [0.9, 0.95, 0.85, 0.9, 0.92], 3: [0.88, 0.9, 0.87, 0.91, 0.9]},
                                        [0.1] * 5, [0.9] * 5), study)
    rises, no_transfer = evaluate_recipe_findings(flat, suite)
    assert not rises.holds and not no_transfer.holds and no_transfer.comparisons[0].p > 0.5
    # with a margin, "m = 3 is within 0.1 of m = 1" holds for the flat curve; the report shows the raw means
    margin = load_suite(write(tmp_path, text.replace("margin = 0.0", "margin = 0.1")))
    rises = evaluate_recipe_findings(flat, margin)[0]
    assert rises.holds and rises.comparisons[0].mean_a == pytest.approx(np.mean([0.88, 0.9, 0.87, 0.91, 0.9]))


def test_the_experiment_script_still_runs_on_the_shared_implementation(tmp_path, capsys):
    module = load_script("recipe_experiments")
    assert module.main(["--kitchens", "kitchen-1", "kitchen-2", "--cv-demos", "3", "--cv-repeats", "1",
                        "--transfer-demos", "3", "--transfer-m", "1", "--transfer-repeats", "1",
                        "--out", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert len(summary["cross_validation"]["kitchen-1"]["bowl"]) == 2  # m = 1, 2
    assert len(summary["transfer"]) == 3 * 2  # 3 sets of training kitchens x 2 test kitchens
    assert (tmp_path / "recipe-cross-validation.png").exists() and (tmp_path / "recipe-transfer.png").exists()
