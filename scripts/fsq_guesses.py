"""The feature question's guessed answers against the teacher's (issue 49 item 3).

Plays the strategies of dialog/data/calibration/fsq-guesses.toml in the training allocation on calibration data
and, on every turn the FSQ is open (``dialog.experiments.fsq_guesses``), compares each guess of the teacher's
answer (``learning.whatif.feature_guesses``) with the change the real answer would make: mean predicted and
realised change, Pearson r and mean absolute error for ACD, IV, PM and held-out accuracy; counts the states
where one label or demonstration question is at least as good as the real answer on every learning feature, and
groups the real answer's one-step change by the examples the learner holds.
Applies the file's rule and prints its verdict; --json ends with one JSON line.

    .venv/bin/python scripts/fsq_guesses.py --data choice|confirmation [--horizon] [--json]
                                            [--datasets N] [--seeds N ...]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dialog.experiments.doc_tables import markdown_table  # noqa: E402
from dialog.experiments.fsq_guesses import by_examples, dominated, guess_table, horizon_table  # noqa: E402
from dialog.experiments.provenance import git_commit  # noqa: E402
from dialog.experiments.whatif_calibration import calibration_specs, run_calibration  # noqa: E402
from learning.datafiles import check_keys, integer, numbers, read_toml, texts  # noqa: E402
from learning.whatif.feature_guesses import GUESSES  # noqa: E402

DEFAULTS = ROOT / "dialog" / "data" / "calibration" / "fsq-guesses.toml"
SHORT = {"classifier_discriminability": "ACD", "instance_variation": "IV", "prediction_margin": "PM",
         "accuracy": "accuracy"}


COMPARED = ["n", "mean predicted", "mean realised", "r", "mean abs. error"]


def compared(row: dict) -> list[str]:
    """A table row's cells under COMPARED."""
    r = "–" if row["correlation"] is None else f"{row['correlation']:.2f}"
    return [str(row["n"]), f"{row['predicted']:+.4f}", f"{row['realised']:+.4f}", r, f"{row['mae']:.4f}"]


def settings() -> dict:
    data, where = read_toml(DEFAULTS, "FSQ-guess settings"), str(DEFAULTS)
    check_keys(data, where, required=("strategies", "guesses", "workers", "choice", "confirmation", "rule"))
    guesses = texts(data, "guesses", where, nonempty=True)
    unknown = sorted(set(guesses) - set(GUESSES))
    if unknown:
        raise SystemExit(f"{where}: guesses: unknown {unknown[0]!r}; accepted: {', '.join(GUESSES)}")
    runs = {}
    for name in ("choice", "confirmation"):
        section, here = data[name], f"{where} [{name}]"
        check_keys(section, here, required=("data_seed", "datasets", "seeds"))
        runs[name] = {"data_seed": integer(section, "data_seed", here, low=101),
                      "datasets": integer(section, "datasets", here, low=1),
                      "seeds": [int(s) for s in numbers(section, "seeds", here, whole=True, low=31)]}
    rule = data["rule"]
    return {"strategies": texts(data, "strategies", where, nonempty=True), "guesses": guesses,
            "workers": integer(data, "workers", where, low=1), "runs": runs,
            "baseline": rule["baseline"], "targets": list(rule["targets"])}


def verdict(rows: list[dict], baseline: str, targets: list[str]) -> list[str]:
    """The guesses that lower the mean absolute error of every rule target against ``baseline``."""
    mae = {(r["guess"], r["target"]): r["mae"] for r in rows}
    return [g for g in dict.fromkeys(r["guess"] for r in rows)
            if g != baseline and all(mae[(g, t)] < mae[(baseline, t)] for t in targets)]


def main(argv=None) -> int:
    config = settings()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", choices=("choice", "confirmation"), required=True)
    parser.add_argument("--datasets", type=int, default=None)
    parser.add_argument("--seeds", type=int, nargs="+", default=None)
    parser.add_argument("--workers", type=int, default=config["workers"])
    parser.add_argument("--horizon", action="store_true",
                        help="also read each guess over the examples the episode can still gather, against the real "
                             "answer's change by the end of the episode")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    run = config["runs"][args.data]
    datasets, seeds = args.datasets or run["datasets"], args.seeds or run["seeds"]
    started = time.perf_counter()
    specs = calibration_specs(config["strategies"], run["data_seed"], datasets, seeds)
    results = run_calibration(specs, args.workers, accuracy_what_if=False, feature_guesses=True, horizon=args.horizon)
    records = [dict(r, strategy=res["strategy"]) for res in results for r in res["feature_guesses"]]
    rows = guess_table(records, config["guesses"])
    early = [r for r in records if r["turn"] <= 5]
    counts = {"states": len(records), "early_states": len(early),
              "real_answer_dominated_early": sum(dominated(r) for r in early),
              "real_answer_dominated_later": sum(dominated(r) for r in records if r["turn"] > 5)}
    for guess in config["guesses"]:
        counts[f"{guess}_dominated_early"] = sum(dominated(r, r["guesses"][guess]["predicted"]) for r in early)
    better = verdict(rows, config["baseline"], config["targets"])
    print(f"{len(records)} states with the FSQ open in {len(specs)} episodes ({', '.join(config['strategies'])}), "
          f"data seed {run['data_seed']}, {datasets} data sets x seeds {seeds}, "
          f"{time.perf_counter() - started:.0f} s")
    print("\n".join(markdown_table(["guess", "target", *COMPARED], [[row["guess"], SHORT[row["target"]], *compared(row)]
                                                                   for row in rows], right_from=2)))
    print(f"turns 1-5: the real answer is dominated by one instance question in "
          f"{counts['real_answer_dominated_early']} of {counts['early_states']} states "
          f"(later turns: {counts['real_answer_dominated_later']} of {len(records) - len(early)})")
    groups = by_examples(records)
    print("\n".join(markdown_table(
        ["examples", "states", "real answer: ACD", "real answer: held-out accuracy", "best instance question: ACD"],
        [[g["examples"], str(g["states"]), f"{g['real_acd']:+.4f}", f"{g['real_accuracy']:+.4f}",
          "–" if g["best_instance_acd"] is None else f"{g['best_instance_acd']:+.4f}"] for g in groups])))
    horizon = horizon_table(records, config["guesses"]) if args.horizon else []
    if horizon:
        print("against the real answer's change by the end of the episode:")
        print("\n".join(markdown_table(
            ["guess", "reading", "target", "turns", *COMPARED],
            [[row["guess"], row["reading"], SHORT[row["target"]], row["turns"], *compared(row)] for row in horizon],
            right_from=4)))
    print("rule (lower MAE than", config["baseline"], "on", ", ".join(SHORT[t] for t in config["targets"]) + "):",
          ", ".join(better) or "no guess passes")
    if args.json:
        print(json.dumps({"data": args.data, "data_seed": run["data_seed"], "datasets": datasets, "seeds": seeds,
                          "commit": git_commit(), "rows": rows, "counts": counts, "by_examples": groups,
                          "horizon": horizon, "better": better,
                          "per_strategy_states": {s: sum(r["strategy"] == s for r in records)
                                                  for s in config["strategies"]}}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
