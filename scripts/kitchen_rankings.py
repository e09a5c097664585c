"""Do the questioners' rankings hold in kitchens they were never run in? (issue 52 item 4)

Runs the plan docs/kitchen-rankings-plan.toml as written: the generated kitchens of its generator seeds, one suite
file a kitchen and run (``extends`` the run's suite with ``kitchen`` and ``only_conditions``, adding the plan's
strategies), kitchen-1 again beside them, every one on the plan's data seeds (``regress --data-seeds``); then
per kitchen each strategy's rank by its pooled mean score and the agreement across the generated kitchens:
Kendall's W (tie-corrected) with a bootstrap interval over kitchens and Friedman's test
(``dialog.experiments.kitchens.rank_agreement``, as ``regress`` does for a suite that names ``kitchens``).
Steps, each resumable (a finished run's replication.json is kept):

    .venv/bin/python scripts/kitchen_rankings.py prepare     # kitchens and suite files
    .venv/bin/python scripts/kitchen_rankings.py render      # every data set, two renderers at a time
    .venv/bin/python scripts/kitchen_rankings.py run         # every suite file on the data seeds
    .venv/bin/python scripts/kitchen_rankings.py analyse [--json]   # rankings.md and rankings.json

``all`` does the four in turn. Everything goes under --results (default results/kitchen-rankings).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bullet_world.generation import generate_kitchens  # noqa: E402
from dialog.experiments.doc_tables import markdown_table  # noqa: E402
from dialog.experiments.kitchens import pooled_means, rank_agreement, read_replication  # noqa: E402
from dialog.experiments.provenance import git_commit  # noqa: E402
from learning.datafiles import check_keys, flag, integer, number, numbers, read_toml, section, tables, text, texts  # noqa: E402,E501
from learning.significance import ranks_high_first  # noqa: E402

PLAN = ROOT / "docs" / "kitchen-rankings-plan.toml"
REFERENCE = "kitchen-1"


def read_plan(path: Path = PLAN) -> dict:
    data, where = read_toml(path, "rankings plan"), str(path)
    check_keys(data, where, required=("generator_seeds", "data_seeds", "seeds", "run", "analysis"),
               optional=("docs", "presets_commit", "budget"))
    first, last = (int(s) for s in numbers(data, "generator_seeds", where, whole=True, low=0, length=2))
    runs = []
    for i, table in enumerate(tables(data, "run", where)):
        here = f"{where} run {i + 1}"
        check_keys(table, here, required=("suite", "condition", "strategies"), optional=("score",))
        runs.append({"suite": text(table, "suite", here), "condition": text(table, "condition", here),
                     "strategies": texts(table, "strategies", here, nonempty=True)})
    analysis = section(data, "analysis", where)
    check_keys(analysis, f"{where} [analysis]", required=("statistic", "bootstrap", "holds_if_lower_bound_at_least"),
               optional=("kitchen_1_reference",))
    return {"generator_seeds": list(range(first, last + 1)),
            "data_seeds": [int(s) for s in numbers(data, "data_seeds", where, whole=True, low=0)],
            "seeds": [int(s) for s in numbers(data, "seeds", where, whole=True, low=0)], "runs": runs,
            "bootstrap": integer(analysis, "bootstrap", f"{where} [analysis]", low=1),
            "holds_at": number(analysis, "holds_if_lower_bound_at_least", f"{where} [analysis]", low=0.0, high=1.0),
            "reference": flag(analysis, "kitchen_1_reference", f"{where} [analysis]", True)}


def kitchens(plan: dict, out: Path) -> dict[str, str]:
    """{label: kitchen as the suite names it}: the generated files (relative to the repository) and kitchen-1."""
    folder = out / "kitchens"
    named = {f"generated-{s}": str(folder / f"generated-{s}.toml") for s in plan["generator_seeds"]}
    return {**named, **({REFERENCE: REFERENCE} if plan["reference"] else {})}


def suite_files(plan: dict, out: Path) -> list[tuple[str, str, Path]]:
    """(run suite, kitchen label, suite file) for every run and kitchen."""
    return [(run["suite"], label, out / "suites" / f"{run['suite']}-{label}.toml")
            for run in plan["runs"] for label in kitchens(plan, out)]


def prepare(plan: dict, out: Path) -> None:
    generate_kitchens(plan["generator_seeds"][0], len(plan["generator_seeds"]), out / "kitchens")
    from dialog.experiments.suite import load_suite

    places = kitchens(plan, out)
    for run in plan["runs"]:
        added = [s for s in run["strategies"] if s not in load_suite(run["suite"]).strategies]
        for label, kitchen in places.items():
            name = f"{run['suite']}-{label}"
            path = out / "suites" / f"{name}.toml"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(f"# written by scripts/kitchen_rankings.py from {PLAN.relative_to(ROOT)}\n"
                            f"extends = {json.dumps(run['suite'])}\nname = {json.dumps(name)}\n"
                            f"kitchen = {json.dumps(kitchen)}\nonly_conditions = {json.dumps([run['condition']])}\n"
                            f"add_strategies = {json.dumps(added)}\n", encoding="utf-8")
    print(f"{len(places)} kitchens and {len(plan['runs']) * len(places)} suite files under {out}")


def _regress(path: Path, plan: dict, *more: str) -> list[str]:
    return [str(Path(sys.executable).parent / "teachbot"), "regress", "--suite", str(path), "--data-seeds",
            *map(str, plan["data_seeds"]), "--no-progress", *more]


def render(plan: dict, out: Path, parallel: int = 2) -> None:
    """Every suite file's data sets, ``parallel`` renderers at a time (rendering runs on one core each)."""
    # the two runs of one kitchen share no data sets (different tasks), so each file is rendered once
    pending = [_regress(path, plan, "--render-only", "--workers", "1") for _, _, path in suite_files(plan, out)]
    running: list[subprocess.Popen] = []
    started = time.perf_counter()
    while pending or running:
        while pending and len(running) < parallel:
            running.append(subprocess.Popen(pending.pop(0), cwd=ROOT))
        time.sleep(1.0)
        for process in [p for p in running if p.poll() is not None]:
            running.remove(process)
            if process.returncode:
                raise SystemExit(f"rendering failed: {' '.join(process.args)}")
    print(f"rendered in {time.perf_counter() - started:.0f} s")


def run(plan: dict, out: Path) -> None:
    for suite, label, path in suite_files(plan, out):
        folder = out / "runs" / f"{suite}-{label}"
        if (folder / "replication.json").exists():
            continue
        subprocess.run(_regress(path, plan, "--results", str(folder)), cwd=ROOT, check=True)


def scores(plan: dict, out: Path) -> dict:
    """{suite: {kitchen label: {strategy: pooled mean score at the condition's last checkpoint}}}."""
    table: dict = {}
    for suite, label, _ in suite_files(plan, out):
        replication = read_replication(out / "runs" / f"{suite}-{label}")
        ((condition, by_strategy),) = pooled_means(replication).items()
        table.setdefault(suite, {})[label] = by_strategy
        table[suite].setdefault("_at", {})[label] = replication["conditions"][0]["strategies"][0]["at"]
    return table


def strategy_holds(reference_rank: float, ranks: np.ndarray) -> bool:
    """The plan's rule: kitchen-1's rank within the generated kitchens' range, and the per-kitchen ranks within
    1 of their median in at least 8 of 10 kitchens (the same share for another count)."""
    close = np.abs(ranks - np.median(ranks)) <= 1.0
    return bool(ranks.min() <= reference_rank <= ranks.max() and close.sum() >= 0.8 * len(ranks))


def analyse(plan: dict, out: Path) -> dict:
    rng = np.random.default_rng(0)
    summary = {"plan": str(PLAN.relative_to(ROOT)), "commit": git_commit(), "data_seeds": plan["data_seeds"],
               "generator_seeds": plan["generator_seeds"], "runs": []}
    for run_plan, (suite, by_kitchen) in zip(plan["runs"], scores(plan, out).items()):
        at = by_kitchen.pop("_at")
        strategies = list(run_plan["strategies"])
        generated = [k for k in by_kitchen if k != REFERENCE]
        agreement = rank_agreement({k: by_kitchen[k] for k in generated}, strategies, rng, plan["bootstrap"])
        means, ranks = np.array(agreement.pop("means")), np.array(agreement.pop("ranks"))
        del agreement["kitchens"], agreement["strategies"]
        reference = (ranks_high_first([by_kitchen[REFERENCE][s] for s in strategies]) if REFERENCE in by_kitchen
                     else None)
        rows = []
        for j, strategy in enumerate(strategies):
            row = {"strategy": strategy, "ranks": ranks[:, j].tolist(), "means": means[:, j].tolist(),
                   "median_rank": float(np.median(ranks[:, j])), "range": [float(ranks[:, j].min()),
                                                                           float(ranks[:, j].max())]}
            if reference is not None:
                row |= {"kitchen_1_rank": float(reference[j]), "kitchen_1_mean": by_kitchen[REFERENCE][strategy],
                        "holds": strategy_holds(reference[j], ranks[:, j])}
            rows.append(row)
        summary["runs"].append({"suite": suite, "condition": run_plan["condition"], "at": at, "kitchens": generated,
                                **agreement, "holds": agreement["ci"][0] >= plan["holds_at"], "strategies": rows})
    write_report(summary, out)
    return summary


def write_report(summary: dict, out: Path) -> None:
    lines = [f"# Rankings across kitchens ({summary['plan']})", "",
             f"Commit {summary['commit']}; data seeds {', '.join(map(str, summary['data_seeds']))}; generator seeds "
             f"{summary['generator_seeds'][0]}-{summary['generator_seeds'][-1]}."]
    for run in summary["runs"]:
        lines += ["", f"## {run['suite']}, condition `{run['condition']}`", "",
                  f"Kendall's W {run['w']:.3f} [95 % CI {run['ci'][0]:.3f}, {run['ci'][1]:.3f}] over "
                  f"{len(run['kitchens'])} kitchens; Friedman chi-squared {run['chi2']:.1f} (df {run['df']}), "
                  f"p {run['p']:.2g}; the ranking {'holds' if run['holds'] else 'does not hold'} across kitchens.", ""]
        header = ["strategy", "kitchen-1 rank (mean)", *[k.replace("generated-", "g") for k in run["kitchens"]],
                  "median", "holds"]
        body = [[row["strategy"], f"{row.get('kitchen_1_rank', float('nan')):g} ({row.get('kitchen_1_mean', 0):.3f})",
                 *[f"{r:g} ({m:.3f})" for r, m in zip(row["ranks"], row["means"])], f"{row['median_rank']:g}",
                 "yes" if row.get("holds") else "no"] for row in run["strategies"]]
        lines += markdown_table(header, body)
    (out / "rankings.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    (out / "rankings.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("step", choices=("prepare", "render", "run", "analyse", "all"))
    parser.add_argument("--results", type=Path, default=Path("results/kitchen-rankings"))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    plan = read_plan()
    for step in (("prepare", "render", "run", "analyse") if args.step == "all" else (args.step,)):
        summary = {"prepare": prepare, "render": render, "run": run, "analyse": analyse}[step](plan, args.results)
    if args.json and isinstance(summary, dict):
        print(json.dumps({"runs": [{k: r[k] for k in ("suite", "w", "ci", "p", "holds")} for r in summary["runs"]]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
