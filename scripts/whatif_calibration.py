"""What-if calibration (issue 49 item 2): the one-step what-if's predicted changes against the realised ones.

DT-iros, DT-task and DT-task-env play the training allocation on calibration data (defaults in
dialog/data/calibration/whatif.toml); for every question they ask, ``dialog.experiments.whatif_calibration``
records E[phi_L(s') | a] - phi_L(s) (eq. 6.3, 7.1) and the predicted change of held-out accuracy beside the
realised changes after the teacher's answer (accuracy: at the turn and by the end of the allocation). Prints a
per-kind table (mean predicted, mean realised, Pearson r, mean absolute error per learning feature), writes a
plot (predicted against realised per kind) and, with --json, ends with one JSON line. Nothing it does changes a
decision (tests/dialog/test_whatif_calibration.py plays an episode with and without the recorder).

    .venv/bin/python scripts/whatif_calibration.py [--json] [--datasets N] [--seeds N ...] [--turns N]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dialog.experiments.provenance import git_commit  # noqa: E402
from dialog.experiments.whatif_calibration import (  # noqa: E402
    KINDS,
    TARGETS,
    calibration_specs,
    calibration_table,
    pairs,
    run_calibration,
)
from learning.datafiles import check_keys, integer, numbers, read_toml, text, texts  # noqa: E402

DEFAULTS = ROOT / "dialog" / "data" / "calibration" / "whatif.toml"
SHORT = {"classifier_discriminability": "ACD", "class_distribution_uniformity": "CDU", "instance_variation": "IV",
         "prediction_margin": "PM", "accuracy_turn": "accuracy at the turn", "accuracy_end": "accuracy by the end"}
KIND_NAMES = {"label": "label (LQ)", "demo": "demonstration (DQ)", "feature": "feature subset (FSQ)"}


def defaults() -> dict:
    data, where = read_toml(DEFAULTS, "what-if calibration defaults"), str(DEFAULTS)
    check_keys(data, where, required=("strategies", "data_seed", "datasets", "seeds", "workers", "plot"))
    return {"strategies": texts(data, "strategies", where, nonempty=True),
            "data_seed": integer(data, "data_seed", where, low=101),
            "datasets": integer(data, "datasets", where, low=1),
            "seeds": [int(s) for s in numbers(data, "seeds", where, whole=True, low=0)],
            "workers": integer(data, "workers", where, low=1), "plot": text(data, "plot", where)}


def markdown(rows: list[dict]) -> list[str]:
    lines = ["| query | what | n | mean predicted | mean realised | r | mean abs. error |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for row in rows:
        r = "–" if row["correlation"] is None else f"{row['correlation']:.2f}"
        lines.append(f"| {KIND_NAMES[row['kind']]} | {SHORT[row['target']]} | {row['n']} | {row['predicted']:+.4f} | "
                     f"{row['realised']:+.4f} | {r} | {row['mae']:.4f} |")
    return lines


def plot(records: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    strategies = sorted({r["strategy"] for r in records})
    fig, axes = plt.subplots(len(KINDS), len(TARGETS), figsize=(3.0 * len(TARGETS), 2.8 * len(KINDS)),
                             squeeze=False)
    for i, kind in enumerate(KINDS):
        for j, target in enumerate(TARGETS):
            ax = axes[i, j]
            for strategy in strategies:
                mine = [r for r in records if r["kind"] == kind and r["strategy"] == strategy]
                if mine:
                    p, q = pairs(mine, target)
                    ax.scatter(p, q, s=8, alpha=0.5, label=strategy)
            low, high = ax.get_xlim() if ax.has_data() else (0, 1)
            lo, hi = min(low, ax.get_ylim()[0]), max(high, ax.get_ylim()[1])
            ax.plot([lo, hi], [lo, hi], color="grey", linewidth=0.8)
            ax.set_title(f"{kind}: {SHORT[target]}", fontsize=9)
            if i == len(KINDS) - 1:
                ax.set_xlabel("predicted change", fontsize=8)
            if j == 0:
                ax.set_ylabel("realised change", fontsize=8)
            ax.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main() -> int:
    base = defaults()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strategies", nargs="+", default=base["strategies"])
    parser.add_argument("--data-seed", type=int, default=base["data_seed"])
    parser.add_argument("--datasets", type=int, default=base["datasets"])
    parser.add_argument("--seeds", type=int, nargs="+", default=base["seeds"])
    parser.add_argument("--turns", type=int, default=None, help="a shorter allocation (default: ch7-training's)")
    parser.add_argument("--workers", type=int, default=base["workers"])
    parser.add_argument("--plot", type=Path, default=ROOT / base["plot"], help="the PNG to write ('' for none)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line (table, per strategy, records)")
    args = parser.parse_args()
    if args.data_seed < 101 or set(args.seeds) & set(range(1, 31)):
        parser.error("calibration data only: --data-seed >= 101 and no episode seed of the demonstrations (1-30)")
    started = time.perf_counter()
    specs = calibration_specs(args.strategies, args.data_seed, args.datasets, args.seeds, args.turns)
    results = run_calibration(specs, args.workers)
    records = [{**r, "strategy": result["strategy"], "dataset": result["dataset"], "seed": result["seed"]}
               for result in results for r in result["records"]]
    table = calibration_table(records)
    seconds = time.perf_counter() - started
    quiet = sum(result["quiet_turns"] for result in results)
    print(f"{len(results)} episodes ({', '.join(args.strategies)}; data seed {args.data_seed}, {args.datasets} data "
          f"set(s) x seeds {' '.join(map(str, args.seeds))}), {len(records)} questions, {quiet} quiet turns; "
          f"{seconds:.0f} s; commit {git_commit()[:7]}")
    print("\n".join(markdown(table)))
    if str(args.plot):
        plot(records, args.plot, f"what-if calibration: {', '.join(args.strategies)}, data seed {args.data_seed}")
        print(f"wrote {args.plot}")
    if args.json:
        per_strategy = {s: calibration_table([r for r in records if r["strategy"] == s]) for s in args.strategies}
        print(json.dumps({"episodes": len(results), "questions": len(records), "quiet_turns": quiet,
                          "seconds": round(seconds, 1), "commit": git_commit(), "table": table,
                          "per_strategy": per_strategy, "records": records}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
