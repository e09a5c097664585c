"""Sensitivity of the settings docs/open-settings.md chose from the thesis's text (issue 53 item 1).

Plays each alternative of dialog/data/calibration/open-settings-sensitivity.toml (the static task's scene rate;
prepare-lunch's state schedule) on calibration data with the suites' own episodes, and prints per suite,
condition, value and strategy: mean final accuracy (± standard error over the data sets), questions asked, turns
played and episodes that reached the turn bound with budget left (the chapter-6 stall); and per condition the
gap between the best DT and the best other strategy. --json ends with one JSON line. Nothing is chosen by it.

    .venv/bin/python scripts/sensitivity_open_settings.py [--json] [--workers N] [--datasets N]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dialog.experiments.doc_tables import markdown_table  # noqa: E402
from dialog.experiments.provenance import git_commit  # noqa: E402
from dialog.experiments.runner import episode_specs, run_locally  # noqa: E402
from dialog.experiments.suite import STATE_SCHEDULES, load_suite  # noqa: E402
from learning.datafiles import check_keys, integer, numbers, read_toml, tables, text, texts  # noqa: E402

SETTINGS = ROOT / "dialog" / "data" / "calibration" / "open-settings-sensitivity.toml"
SETTABLE = ("change_every", "state_schedule")


def read_settings(path: Path = SETTINGS) -> dict:
    data, where = read_toml(path, "sensitivity settings"), str(path)
    check_keys(data, where, required=("data_seed", "datasets", "seeds", "workers", "variant"))
    variants = []
    for i, table in enumerate(tables(data, "variant", where)):
        here = f"{where} variant {i + 1}"
        check_keys(table, here, required=("suite", "conditions", "strategies", "setting", "values"))
        setting = text(table, "setting", here, choices=SETTABLE)
        values = (numbers(table, "values", here, whole=True, low=1) if setting == "change_every"
                  else texts(table, "values", here, nonempty=True, choices=STATE_SCHEDULES))
        variants.append({"suite": text(table, "suite", here), "conditions": texts(table, "conditions", here),
                         "strategies": texts(table, "strategies", here, nonempty=True), "setting": setting,
                         "values": [int(v) if setting == "change_every" else v for v in values]})
    return {"data_seed": integer(data, "data_seed", where, low=100),
            "datasets": integer(data, "datasets", where, low=1),
            "seeds": [int(s) for s in numbers(data, "seeds", where, whole=True, low=0)],
            "workers": integer(data, "workers", where, low=1), "variants": variants}


def variant_suite(variant: dict, value, config: dict):
    """The shipped suite cut to the variant's conditions and strategies, with ``setting`` = ``value``."""
    suite = load_suite(variant["suite"])
    chosen = [c for c in suite.conditions if c.name in variant["conditions"]]
    missing = sorted(set(variant["conditions"]) - {c.name for c in chosen})
    if missing:
        raise SystemExit(f"{SETTINGS}: suite {variant['suite']} has no condition {missing[0]!r}")
    conditions = tuple(replace(c, **{variant["setting"]: value}) for c in chosen)
    return replace(suite, conditions=conditions, strategies=tuple(variant["strategies"]), datasets=config["datasets"],
                   seeds=tuple(config["seeds"]), data_seed=config["data_seed"], findings=())


def summarise(results: list[dict]) -> list[dict]:
    rows = {}
    for result in results:
        spec = result["spec"]
        key = (spec["condition"]["name"], spec["strategy"])
        rows.setdefault(key, []).append(result)
    summary = []
    for (condition, strategy), mine in rows.items():
        accuracy = np.array([r["accuracy"] for r in mine])
        bound = [r["spec"]["condition"]["turns"] for r in mine]
        budget = [r["spec"]["condition"]["budget"] for r in mine]
        at_bound = sum(r["series"]["turn"][-1] >= b and r["series"]["spent"][-1] < s - 1e-9
                       for r, b, s in zip(mine, bound, budget))
        summary.append({"condition": condition, "strategy": strategy, "episodes": len(mine),
                        "accuracy": float(accuracy.mean()),
                        "se": float(accuracy.std(ddof=1) / np.sqrt(len(mine))) if len(mine) > 1 else None,
                        "questions": float(np.mean([r["series"]["questions"][-1] for r in mine])),
                        "turns": float(np.mean([r["series"]["turn"][-1] for r in mine])), "at_bound": int(at_bound)})
    return summary


def dt_gap(summary: list[dict]) -> dict[str, float]:
    """Per condition: the best DT strategy's mean accuracy minus the best other's."""
    gaps = {}
    for condition in dict.fromkeys(r["condition"] for r in summary):
        mine = [r for r in summary if r["condition"] == condition]
        dts = [r["accuracy"] for r in mine if r["strategy"].startswith("dt")]
        others = [r["accuracy"] for r in mine if not r["strategy"].startswith("dt")]
        if dts and others:
            gaps[condition] = max(dts) - max(others)
    return gaps


def main(argv=None) -> int:
    config = read_settings()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=config["workers"])
    parser.add_argument("--datasets", type=int, default=None)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.datasets:
        config["datasets"] = args.datasets
    started, report = time.perf_counter(), []
    with tempfile.TemporaryDirectory(prefix="teachbot-sensitivity-") as scratch:
        for variant in config["variants"]:
            for value in variant["values"]:
                suite = variant_suite(variant, value, config)
                out = Path(scratch) / f"{variant['suite']}-{variant['setting']}-{value}"
                results = run_locally(episode_specs(suite, out), args.workers, progress=False)
                summary = summarise(results)
                report.append({"suite": variant["suite"], "setting": variant["setting"], "value": value,
                               "rows": summary, "dt_gap": dt_gap(summary)})
                print(f"\n{variant['suite']}, {variant['setting']} = {value} (data seed {config['data_seed']}, "
                      f"{config['datasets']} data sets x seeds {config['seeds']}):")
                print("\n".join(markdown_table(
                    ["condition", "strategy", "final accuracy", "questions", "turns", "at the bound"],
                    [[r["condition"], r["strategy"],
                      f"{r['accuracy']:.3f}" + ("" if r["se"] is None else f" ± {r['se']:.3f}"),
                      f"{r['questions']:.1f}", f"{r['turns']:.1f}", f"{r['at_bound']} of {r['episodes']}"]
                     for r in summary], right_from=2)))
                for condition, gap in report[-1]["dt_gap"].items():
                    print(f"best DT minus best other, {condition}: {gap:+.3f}")
    seconds = time.perf_counter() - started
    print(f"\n{seconds:.0f} s")
    if args.json:
        print(json.dumps({"commit": git_commit(), "data_seed": config["data_seed"], "datasets": config["datasets"],
                          "seeds": config["seeds"], "report": report, "seconds": round(seconds, 1)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
