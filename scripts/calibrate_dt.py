"""Apply the committed calibration rule: pick the hand-set DT presets' weights on calibration data (issue 39).

The rule (``dialog/data/calibration/dt-weights.toml``, docs/calibration.md) names for each preset one weight
and a grid of values for it, the conditions and the calibration data (data seeds >= 100). This script plays
every value on every condition, data seed, training data set and episode seed (the real dialog manager and
scripted teacher, as ``teachbot regress`` does), picks per preset the value with the highest mean final
accuracy (ties to the smaller), and writes one weights file per preset, with its provenance (commit, rule
file and its SHA-256, data seeds, every grid value's accuracy), into ``--out``. It never writes the shipped
presets: copying a file from ``--out`` to learning/decision/presets/ is a commit of its own.

    python scripts/calibrate_dt.py --dry-run             # the plan and a time estimate, nothing played
    python scripts/calibrate_dt.py --out results/calibration/chosen --json
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from dialog.experiments.calibration import RULE_FILE, Rule, calibrate, load_rule, plan_suites, write_choices
from learning.datafiles import check_keys, number, read_toml, tables, text
from learning.errors import TeachbotError

COST_FILE = RULE_FILE.parent / "cost.toml"  # measured seconds per episode by condition (docs/calibration.md)


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rule", type=Path, default=RULE_FILE, help=f"the rule file (default {RULE_FILE.name})")
    parser.add_argument("--out", type=Path, default=Path("results/calibration/chosen"),
                        help="folder for the chosen weights, one NAME.toml per preset "
                             "(default results/calibration/chosen)")
    parser.add_argument("--results", type=Path, default=Path("results/calibration"),
                        help="folder for the episodes' transcripts (default results/calibration)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="worker processes (default: every core)")
    parser.add_argument("--dry-run", action="store_true", help="print the plan and a time estimate; play nothing")
    parser.add_argument("--no-progress", action="store_true", help="no progress line")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error(f"--workers must be at least 1, got {args.workers}")
    return args


def seconds_per_episode(path: Path = COST_FILE) -> dict[str, float]:
    """{"suite/condition": measured seconds of one episode (one core)} from the cost file ({} without one)."""
    if not path.is_file():
        return {}
    table = read_toml(path, "calibration cost")
    check_keys(table, str(path), required=("measured",), optional=("machine", "command", "commit"))
    measured = {}
    for index, row in enumerate(tables(table, "measured", str(path), nonempty=True)):
        where = f"{path} measured {index + 1}"
        check_keys(row, where, required=("condition", "seconds_per_episode"), optional=("episodes",))
        measured[text(row, "condition", where)] = number(row, "seconds_per_episode", where, above=0.0)
    return measured


def plan(rule: Rule, workers: int) -> dict:
    """What the rule will play, and how long it should take at the measured cost per episode."""
    costs, per_condition = seconds_per_episode(), []
    values = sum(len(p.grid) for p in rule.presets)
    for condition in rule.conditions:
        key = f"{condition.suite}/{condition.name}"
        episodes = values * len(rule.data_seeds) * rule.datasets * len(rule.seeds)
        seconds = costs.get(key) if condition.turns is None and condition.budget is None else None
        per_condition.append({"condition": key, "episodes": episodes, "seconds_per_episode": seconds})
    known = all(c["seconds_per_episode"] is not None for c in per_condition)
    estimate = sum(c["episodes"] * c["seconds_per_episode"] for c in per_condition) / workers if known else None
    return {"rule": str(rule.path), "rule_sha256": rule.sha256, "data_seeds": list(rule.data_seeds),
            "datasets": rule.datasets, "seeds": list(rule.seeds),
            "presets": [{"name": p.name, "base": p.base, "feature": p.feature, "grid": list(p.grid)}
                        for p in rule.presets],
            "conditions": per_condition, "episodes": rule.episodes, "workers": workers,
            "suites": [f"{s.name} (data seed {s.data_seed})" for s in plan_suites(rule)],
            "estimated_seconds": None if estimate is None else round(estimate)}


def _say_plan(facts: dict, say=print) -> None:
    say(f"rule {facts['rule']} (sha256 {facts['rule_sha256'][:12]}): data seeds "
          f"{', '.join(map(str, facts['data_seeds']))}, {facts['datasets']} data sets, seeds "
          f"{', '.join(map(str, facts['seeds']))}")
    for preset in facts["presets"]:
        say(f"  {preset['name']}: {preset['feature']} of {preset['base']} from {preset['grid']}")
    for condition in facts["conditions"]:
        cost = condition["seconds_per_episode"]
        say(f"  {condition['condition']}: {condition['episodes']} episodes"
              + (f", {cost:g} s each as measured" if cost else ", cost per episode not measured"))
    estimate = facts["estimated_seconds"]
    say(f"{facts['episodes']} episodes on {facts['workers']} workers: "
          + (f"about {estimate / 3600:.1f} h ({estimate} s), plus rendering any calibration data not yet cached"
             if estimate is not None else f"no estimate (a condition's cost is not in {COST_FILE.name})"))


def main(args) -> int:
    rule = load_rule(args.rule)
    facts = plan(rule, args.workers)
    say = print if not args.json else (lambda line: print(line, file=sys.stderr))  # --json: stdout is the JSON
    _say_plan(facts, say)
    if args.dry_run:
        if args.json:
            print(json.dumps(facts))
        return 0
    started = time.perf_counter()
    choices, ran = calibrate(rule, args.results, args.workers, progress=not args.no_progress, say=say)
    written = write_choices(choices, rule, ran, args.out)
    summary = {**facts, **ran, "wall_seconds": round(time.perf_counter() - started, 1),
               "seconds_per_episode": round(ran["episode_seconds"] / max(ran["episodes"], 1), 2),
               "choices": [{"preset": c.preset.name, "chosen": c.chosen,
                            "grid": [{"value": v, "mean_final_accuracy": a, "episodes": n}
                                     for v, a, n in zip(c.preset.grid, c.accuracies, c.episodes)]}
                           for c in choices], "written": [str(p) for p in written]}
    for choice in choices:
        grid = ", ".join(f"{v:g}: {a:.4f}" for v, a in zip(choice.preset.grid, choice.accuracies))
        say(f"{choice.preset.name}: {choice.preset.feature} = {choice.chosen:g} (mean final accuracy {grid})")
    say(f"{ran['episodes']} episodes in {summary['wall_seconds']} s ({summary['seconds_per_episode']} s of "
        f"episode time each); weights written to {', '.join(map(str, written))}")
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(_parse(sys.argv[1:])))
    except TeachbotError as error:  # a rule file, suite or setting we cannot run: one line, no traceback
        sys.exit(f"calibrate_dt: {error}")
