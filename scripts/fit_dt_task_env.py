"""Learn the shipped DT-task-env weights (issue 39's plan), or refit issue 27's eleven-feature dt-task-env-v1.

By default follows learning/irl/fit-plan-dt-task-env.toml: per-turn MaxEnt IRL (eq. 7.5-7.7) on the thesis's
seven features with the thesis's signs, issue 27's protocol (learning.irl.imitation) on the shipped
demonstrations (learning/irl/expert-demos/, the scripted expert in ch7-training on data seed 100); writes
learning/decision/presets/dt-task-env.toml with its provenance and the fit report
learning/irl/fit-report-dt-task-env.json. ``--eleven`` refits issue 27's seven-plus-habits weights instead
(dt-task-env-v1.toml, its ablations dt-task-env-no-env.toml and dt-task-habits.toml by the rule fixed in
advance, ``ablation_weights``, and fit-report-dt-task-env-v1.json). docs/irl.md.

    .venv/bin/python scripts/fit_dt_task_env.py [--eleven] [--json] [--no-check]

The ship rule requires the rollout check (issue 49, learning/irl/rollout-check.toml) of the written weights: the
report records it, and the script exits 1 when it fails (--no-check skips it: the rule is then not judged).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dialog.experiments.irl_rollouts import training_condition  # noqa: E402
from dialog.experiments.provenance import git_commit  # noqa: E402
from dialog.experiments.rollout_check import checked_strategy, run_check, ship_rule_record  # noqa: E402
from learning.datafiles import read_toml  # noqa: E402
from learning.decision.weights import WEIGHTS_DIRECTORY  # noqa: E402
from learning.decision.weights_file import DecisionWeights, load_weights, save_weights  # noqa: E402
from learning.irl.imitation import ablation_weights  # noqa: E402
from learning.irl.learn import SHIPPED, learn_imitation_weights, weights_comment  # noqa: E402
from learning.irl.rollout_check import load_check_settings  # noqa: E402

IRL = ROOT / "learning" / "irl"
PLAN = IRL / "fit-plan-dt-task-env.toml"
ABLATION_COMMENTS = {
    "dt-task-env-no-env": "Issue 27's ablation A: dt-task-env-v1's weights with the budget and clock features "
                          "(budget_consumption, remaining_time,\nnon_query_time, pace_overrun, "
                          "feature_query_overdue) set to 0. Written by scripts/fit_dt_task_env.py --eleven; "
                          "docs/irl.md.",
    "dt-task-habits": "Issue 27's ablation B: DT-task's learning weights (scaled to dt-task-env-v1's learning-weight "
                      "norm) with dt-task-env-v1's\nhabit-feature weights. Written by scripts/fit_dt_task_env.py "
                      "--eleven; docs/irl.md.",
}
SEVEN_COMMENT = ("DT-task-env weights (thesis eq. 7.2): per-turn maximum-entropy IRL (eq. 7.5-7.7) on the thesis's "
                 "seven features with the thesis's signs,\nby the plan learning/irl/fit-plan-dt-task-env.toml "
                 "(issue 39), committed before the fit. Written by scripts/fit_dt_task_env.py; docs/irl.md.")


def plan_signs(plan: dict) -> tuple[tuple[str, int], ...]:
    """The plan's [signs] table as (feature, +1 | -1) pairs, in the file's order."""
    return tuple((name, int(sign)) for name, sign in plan["signs"].items())


def fit_seven(commit: str):
    """The plan's fit: dt-task-env.toml and its report."""
    plan = read_toml(PLAN, "the DT-task-env fit plan")
    fit = plan["fit"]
    learned = learn_imitation_weights(fit["demos"], tuple(fit["split_seeds"]), tuple(fit["fit_seeds"]),
                                      fit["iterations"], features=fit["features"], signs=plan_signs(plan),
                                      context={"commit": commit, "plan": str(PLAN.relative_to(ROOT)),
                                               **training_condition().provenance()})
    save_weights(WEIGHTS_DIRECTORY / "dt-task-env.toml", learned.weights, SEVEN_COMMENT)
    return learned, IRL / "fit-report-dt-task-env.json"


def fit_eleven(commit: str):
    """Issue 27's fit: dt-task-env-v1.toml, its two ablations and its report."""
    learned = learn_imitation_weights(SHIPPED, context={"commit": commit, **training_condition().provenance()})
    save_weights(WEIGHTS_DIRECTORY / "dt-task-env-v1.toml", learned.weights, weights_comment(learned))
    dt_task = load_weights(WEIGHTS_DIRECTORY / "dt-task-v1.toml").as_dict()
    for name, values in ablation_weights(learned.weights.as_dict(), dt_task).items():
        provenance = {"method": "ablation of dt-task-env-v1 (issue 27)",
                      "derived_from": "dt-task-env-v1.toml, dt-task-v1.toml",
                      "commit": commit, "rule": "learning.irl.imitation.ablation_weights"}
        weights = DecisionWeights(tuple(values), tuple(values.values()), provenance)
        save_weights(WEIGHTS_DIRECTORY / f"{name}.toml", weights, ABLATION_COMMENTS[name])
    return learned, IRL / "fit-report-dt-task-env-v1.json"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--eleven", action="store_true", help="refit issue 27's dt-task-env-v1 and its ablations")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--no-check", action="store_true", help="skip the rollout check the ship rule requires")
    args = parser.parse_args()
    commit = git_commit()
    learned, report_path = fit_eleven(commit) if args.eleven else fit_seven(commit)
    preset = WEIGHTS_DIRECTORY / ("dt-task-env-v1.toml" if args.eleven else "dt-task-env.toml")
    checked = None if args.no_check else run_check(load_check_settings(), checked_strategy(str(preset)))
    summary = {**learned.summary(), **ship_rule_record(checked)}
    report_path.write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    report = learned.report
    print(f"{len(learned.fits)} fits in {learned.seconds:.1f} s; kept {report['policy']} split "
          f"{report['kept']['split_seed']} fit seed {report['kept']['fit_seed']}")
    print(json.dumps({"kept_held_out": report["kept"]["held_out"], "held_out_spread": report["held_out_spread"],
                      "baselines_on_kept_held_out": report["baselines_on_kept_held_out"],
                      "same_features_without_signs": report["same_features_without_signs"],
                      "thesis_features_per_turn_fit": report["thesis_features_per_turn_fit"]}, indent=1))
    for name, value in learned.weights.as_dict().items():
        print(f"  {name:<30} {value:>12.4f}")
    passes = summary["ship_rule"]["passes"]
    print("ship rule: " + {None: "not judged (--no-check)", True: "passes", False: "FAILS (its rollout check failed)"}[
        passes])
    if args.json:
        print(json.dumps(summary))
    return 1 if passes is False else 0


if __name__ == "__main__":
    sys.exit(main())
