"""Learn the shipped DT-task-env weights and write issue 27's two ablation presets (docs/irl.md).

Runs ``teachbot learn-weights``'s imitation protocol (learning.irl.imitation) on the shipped demonstrations
(learning/irl/expert-demos/, the scripted expert in ch7-training on data seed 100), writes
learning/decision/presets/dt-task-env.toml with its provenance, the ablations dt-task-env-no-env.toml and
dt-task-habits.toml derived from it by the rule fixed in advance (``ablation_weights``), and the fit report
to --report (default learning/irl/fit-report-dt-task-env.json).

    .venv/bin/python scripts/fit_dt_task_env.py [--json]
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
from learning.decision.weights import WEIGHTS_DIRECTORY  # noqa: E402
from learning.decision.weights_file import DecisionWeights, load_weights, save_weights  # noqa: E402
from learning.irl.imitation import ablation_weights  # noqa: E402
from learning.irl.learn import SHIPPED, learn_imitation_weights, weights_comment  # noqa: E402

REPORT = ROOT / "learning" / "irl" / "fit-report-dt-task-env.json"
ABLATION_COMMENTS = {
    "dt-task-env-no-env": "Issue 27's ablation A: dt-task-env's weights with the budget and clock features "
                          "(budget_consumption, remaining_time,\nnon_query_time, pace_overrun, "
                          "feature_query_overdue) set to 0. Written by scripts/fit_dt_task_env.py; docs/irl.md.",
    "dt-task-habits": "Issue 27's ablation B: DT-task's learning weights (scaled to dt-task-env's learning-weight "
                      "norm) with dt-task-env's\nhabit-feature weights. Written by scripts/fit_dt_task_env.py; "
                      "docs/irl.md.",
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--report", type=Path, default=REPORT)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    commit = git_commit()
    learned = learn_imitation_weights(SHIPPED, context={"commit": commit, **training_condition().provenance()})
    save_weights(WEIGHTS_DIRECTORY / "dt-task-env.toml", learned.weights, weights_comment(learned))
    dt_task = load_weights(WEIGHTS_DIRECTORY / "dt-task.toml").as_dict()
    for name, values in ablation_weights(learned.weights.as_dict(), dt_task).items():
        provenance = {"method": "ablation of dt-task-env (issue 27)", "derived_from": "dt-task-env.toml, dt-task.toml",
                      "commit": commit, "rule": "learning.irl.imitation.ablation_weights"}
        weights = DecisionWeights(tuple(values), tuple(values.values()), provenance)
        save_weights(WEIGHTS_DIRECTORY / f"{name}.toml", weights, ABLATION_COMMENTS[name])
    args.report.write_text(json.dumps(learned.summary(), indent=1) + "\n", encoding="utf-8")
    report = learned.report
    print(f"{len(learned.fits)} fits in {learned.seconds:.1f} s; kept {report['policy']} split "
          f"{report['kept']['split_seed']} fit seed {report['kept']['fit_seed']}")
    print(json.dumps({"kept_held_out": report["kept"]["held_out"], "held_out_spread": report["held_out_spread"],
                      "baselines_on_kept_held_out": report["baselines_on_kept_held_out"],
                      "baselines_spread": report["baselines_spread"],
                      "thesis_features_per_turn_fit": report["thesis_features_per_turn_fit"]}, indent=1))
    for name, value in learned.weights.as_dict().items():
        print(f"  {name:<30} {value:>12.4f}")
    if args.json:
        print(json.dumps(learned.summary()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
