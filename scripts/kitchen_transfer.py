"""Transfer of recipe groundings across many kitchens (issue 52 item 3, docs/kitchen-transfer-plan.toml).

Runs the kitchen-transfer suite (the kitchen-pairs arm over 40 generated kitchens and the shipped three) and,
beside it, the recipes suite's situated/elsewhere arms in the shipped three (the thesis's three-kitchen result,
§4.4.2); then says for each recipe whether transfer falls with distance (the plan's criterion, computed by the
suite: dialog/experiments/recipes/kitchen_pairs.py) and whether the most distant fifth of the ordered pairs
scores no better than the elsewhere arm's 95 % interval (the thesis's finding reproduced).

    .venv/bin/python scripts/kitchen_transfer.py run        # both suites (about an hour on 2 cores)
    .venv/bin/python scripts/kitchen_transfer.py analyse [--json]   # transfer.md, transfer.json, transfer-*.png
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dialog.experiments.provenance import git_commit  # noqa: E402
from dialog.experiments.recipes.kitchen_pairs import plot  # noqa: E402

PLAN = ROOT / "docs" / "kitchen-transfer-plan.toml"
BOOTSTRAP = 2_000  # the plan's [criterion] bootstrap
M = 5              # the plan's criterion is on m = 5


def run(out: Path) -> None:
    teachbot = str(Path(sys.executable).parent / "teachbot")
    for suite, folder, more in (("kitchen-transfer", "pairs", []),
                                ("recipes", "reference", ["--strategies", "situated", "elsewhere"])):
        if not (out / folder / "report.md").exists():
            subprocess.run([teachbot, "regress", "--suite", suite, "--results", str(out / folder), "--no-progress",
                            *more], cwd=ROOT, check=True)


def elsewhere_interval(runs_csv: Path, recipe: str, rng: np.random.Generator) -> dict:
    """The recipes suite's elsewhere arm at m = 5: mean parameter match per trial, its mean and a 95 %
    percentile bootstrap interval over trials."""
    trials: dict[tuple, list[float]] = defaultdict(list)
    with open(runs_csv, newline="") as handle:
        for row in csv.DictReader(handle):
            if (row["experiment"] == "transfer" and row["recipe"] == recipe and int(row["m"]) == M
                    and row["kitchen"] not in row["trained_in"].split("+")):
                trials[(row["seed"], row["kitchen"], row["trained_in"], row["repeat"])].append(float(row["accuracy"]))
    values = np.array([np.mean(v) for v in trials.values()])
    means = [values[rng.integers(0, len(values), len(values))].mean() for _ in range(BOOTSTRAP)]
    return {"trials": len(values), "mean": float(values.mean()),
            "ci": [float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))]}


def analyse(out: Path) -> dict:
    rng = np.random.default_rng(0)
    summary = {"plan": str(PLAN.relative_to(ROOT)), "commit": git_commit(), "recipes": []}
    for path in sorted((out / "pairs").glob("kitchen-pairs-*.json")):
        data = json.loads(path.read_text(encoding="utf-8"))
        recipe = data["recipe"]
        reference = elsewhere_interval(out / "reference" / "runs.csv", recipe, rng)
        at_m = next(a for a in data["analyses"] if a["m"] == M)
        plot(data, out / f"transfer-{recipe}.png", reference)
        executed = data["executions"]
        summary["recipes"].append({
            "recipe": recipe, "analyses": data["analyses"], "paired": data["paired"], "elsewhere": reference,
            "top_quintile_match": at_m["means"][-1],
            "thesis_reproduced": bool(at_m["means"][-1] <= reference["ci"][1]),
            "executions": {"pairs": len(executed), "succeeded": sum(e["success"] for e in executed),
                           "by_quintile": _executions_by_quintile(executed, at_m["edges"])}})
    write(summary, out)
    return summary


def _executions_by_quintile(executed: list[dict], edges: list[float]) -> list[list[int]]:
    inner = np.asarray(edges[1:-1])
    bins = np.searchsorted(inner, [e["distance"] for e in executed], side="right")
    return [[int(sum(e["success"] for e, b in zip(executed, bins) if b == q)), int(np.sum(bins == q))]
            for q in range(len(edges) - 1)]


def write(summary: dict, out: Path) -> None:
    lines = [f"# Transfer across kitchens ({summary['plan']})", "", f"Commit {summary['commit']}.", ""]
    for r in summary["recipes"]:
        lines += [f"## {r['recipe']}", ""]
        for a in r["analyses"]:
            lines.append(f"- m = {a['m']}: Spearman rho {a['rho']:.3f} over {a['pairs']} ordered pairs, permutation "
                         f"p (less) {a['p']:.4f}: transfer {'falls' if a['falls'] else 'does not fall'} with distance; "
                         "per quintile " + ", ".join(f"{m:.3f} [{lo:.3f}, {hi:.3f}]"
                                                     for m, lo, hi in zip(a["means"], a["low"], a["high"])))
        e = r["elsewhere"]
        lines += [f"- elsewhere arm (shipped three, m = {M}): {e['mean']:.3f} [{e['ci'][0]:.3f}, {e['ci'][1]:.3f}] "
                  f"over {e['trials']} trials; top distance quintile {r['top_quintile_match']:.3f}: the thesis's "
                  f"no-transfer finding is {'reproduced' if r['thesis_reproduced'] else 'not reproduced'}",
                  f"- executed: {r['executions']['succeeded']} of {r['executions']['pairs']} "
                  "(per quintile " + ", ".join(f"{s}/{n}" for s, n in r["executions"]["by_quintile"]) + ")", ""]
    (out / "transfer.md").write_text("\n".join(lines), encoding="utf-8")
    (out / "transfer.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("step", choices=("run", "analyse", "all"))
    parser.add_argument("--results", type=Path, default=Path("results/kitchen-transfer"))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.step in ("run", "all"):
        run(args.results)
    if args.step in ("analyse", "all"):
        summary = analyse(args.results)
        if args.json:
            print(json.dumps({r["recipe"]: {"falls": [a["falls"] for a in r["analyses"]],
                                            "thesis_reproduced": r["thesis_reproduced"]} for r in summary["recipes"]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
