"""Thesis ch. 4 experiments in the simulated kitchens: learning curves and transfer between kitchens.

Within-kitchen cross-validation (the shape of thesis figure 4.6): serve-pasta,
n demonstrations per kitchen (default 12: six arrangements under two lighting
conditions). For every m = 1..n-1, ``--cv-repeats`` times: draw m training
demonstrations uniformly at random, learn every parameter model, and test each
parameter on the n - m held-out demonstrations (thesis §4.3.4).

Between-kitchen transfer (the shape of figure 4.8): serve-salad, 6
demonstrations per kitchen under one lighting. For every non-empty set of
training kitchens and m in ``--transfer-m``, ``--transfer-repeats`` times: m
random demonstrations from *each* training kitchen make one (aggregate) model,
tested on the demonstrations of the test kitchen that were not used to train.

Writes plots to ``--out`` (docs/img by default), prints Markdown tables, and
with ``--json`` ends with one JSON line of all numbers. One ``--seed`` drives
every random choice.

    python scripts/recipe_experiments.py --json
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from bullet_world.catalogue import load_kitchen
from bullet_world.recipe_tracking import match_rows
from bullet_world.recipe_world import RecipeDemonstration, RecipeWorld
from dialog.commands._recipe_session import evaluate_demonstration, ground, parameter_names, recipe_steps
from learning.recipe import Recipe, load_builtin_recipe, recipe_parameters

DEFAULT_KITCHENS = ("kitchen-1", "kitchen-2", "kitchen-3")
# Objects dashed, locations solid (the three object curves often coincide: lighting decides them).
OBJECT_STYLES = tuple({"linestyle": "--", "marker": m, "markersize": 5, "alpha": 0.8} for m in ("o", "s", "^"))
LOCATION_STYLES = tuple({"linestyle": "-", "marker": m, "markersize": 3} for m in ("o", "v", "D", "x"))


def collect(recipe: Recipe, task: str, kitchen: str, count: int, seed: int) -> list[RecipeDemonstration]:
    """``count`` scripted demonstrations of ``recipe`` in ``kitchen`` (camera + perception, no arm)."""
    with RecipeWorld(recipe_steps(recipe), task=task, kitchen=kitchen, seed=seed) as world:
        return world.demonstrate(count, np.random.default_rng([seed, 11]))


def accuracy(recipe: Recipe, train: list[RecipeDemonstration], test: list[RecipeDemonstration],
             rng: np.random.Generator) -> dict[str, float]:
    """Fraction of successful trials per parameter when trained on ``train`` and tested on ``test``."""
    grounding = ground(recipe, train, rng)
    trials: dict[str, list[bool]] = {name: [] for name in parameter_names(recipe)}
    for demonstration in test:
        for name, results in evaluate_demonstration(grounding, recipe, demonstration).items():
            trials[name].extend(results)
    return {name: float(np.mean(results)) for name, results in trials.items()}


def cross_validation(recipe: Recipe, demos: list[RecipeDemonstration], repeats: int,
                     rng: np.random.Generator) -> dict[str, list[float]]:
    """Mean accuracy per parameter for m = 1..n-1 training demonstrations (figure 4.6)."""
    n = len(demos)
    curves: dict[str, list[float]] = {name: [] for name in parameter_names(recipe)}
    for m in range(1, n):
        runs = []
        for _ in range(repeats):
            chosen = set(rng.choice(n, size=m, replace=False).tolist())
            train = [demos[i] for i in sorted(chosen)]
            test = [demos[i] for i in range(n) if i not in chosen]
            runs.append(accuracy(recipe, train, test, rng))
        for name in curves:
            curves[name].append(float(np.mean([run[name] for run in runs])))
    return curves


def edit_distance(first: RecipeDemonstration, second: RecipeDemonstration) -> float:
    """Environment edit distance of two demonstrations (eq. 4.4), over their initial states.

    Eq. 4.4 sums dist (eq. 4.1) over every pair of objects; here each object is paired with itself
    (rows matched by ``recipe_tracking``), so objects that stay put add nothing.
    """
    a, b = first.steps[0].before, second.steps[0].before
    order = match_rows(a.appearance, a.locations, b.appearance, b.locations)
    return float(np.sum(np.linalg.norm(b.locations[order] - a.locations, axis=1)))


def varied_pairs(recipe: Recipe, demos: list[RecipeDemonstration], rng: np.random.Generator) -> dict:
    """Every pair of demonstrations as training set (m = 2): mean accuracy of the third of pairs with
    the largest edit distance vs. the third with the smallest (thesis §4.4.1, figure 4.7)."""
    rows = []
    for i, j in itertools.combinations(range(len(demos)), 2):
        test = [d for k, d in enumerate(demos) if k not in (i, j)]
        result = accuracy(recipe, [demos[i], demos[j]], test, rng)
        rows.append((edit_distance(demos[i], demos[j]), float(np.mean(list(result.values())))))
    rows.sort()
    third = max(1, len(rows) // 3)
    return {"pairs": len(rows), "least_varied_accuracy": float(np.mean([a for _, a in rows[:third]])),
            "most_varied_accuracy": float(np.mean([a for _, a in rows[-third:]])),
            "least_varied_distance_m": float(np.mean([d for d, _ in rows[:third]])),
            "most_varied_distance_m": float(np.mean([d for d, _ in rows[-third:]]))}


def transfer(recipe: Recipe, demos: dict[str, list[RecipeDemonstration]], m_values: list[int], repeats: int,
             rng: np.random.Generator) -> list[dict]:
    """Accuracy per parameter in every test kitchen for models trained in every set of kitchens (figure 4.8)."""
    kitchens = list(demos)
    rows = []
    for m in m_values:
        for size in range(1, len(kitchens) + 1):
            for training in itertools.combinations(kitchens, size):
                for test_kitchen in kitchens:
                    runs = []
                    for _ in range(repeats):
                        train, used = [], {}
                        for kitchen in training:
                            chosen = sorted(rng.choice(len(demos[kitchen]), size=m, replace=False).tolist())
                            used[kitchen] = set(chosen)
                            train.extend(demos[kitchen][i] for i in chosen)
                        held_out = used.get(test_kitchen, set())
                        test = [d for i, d in enumerate(demos[test_kitchen]) if i not in held_out]
                        runs.append(accuracy(recipe, train, test, rng))
                    mean = {name: float(np.mean([run[name] for run in runs])) for name in runs[0]}
                    rows.append({"m": m, "train": list(training), "test": test_kitchen,
                                 "situated": test_kitchen in training, "accuracy": mean,
                                 "mean": float(np.mean(list(mean.values())))})
    return rows


def plot_cross_validation(curves: dict[str, dict[str, list[float]]], objects: tuple[str, ...], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(curves), figsize=(4.6 * len(curves), 3.8), squeeze=False, sharey=True)
    for axis, (kitchen, per_parameter) in zip(axes[0], curves.items()):
        for number, (name, values) in enumerate(per_parameter.items()):
            styles = OBJECT_STYLES if name in objects else LOCATION_STYLES
            axis.plot(range(1, len(values) + 1), values, label=name, **styles[number % len(styles)])
        axis.set_title(f"serve-pasta, {kitchen}")
        axis.set_xlabel("training demonstrations m")
        axis.set_ylim(-0.02, 1.02)
        axis.grid(alpha=0.3)
    axes[0][0].set_ylabel("accuracy on held-out demonstrations")
    axes[0][-1].legend(fontsize=8, loc="lower right")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_transfer(rows: list[dict], test_kitchen: str, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m_values = sorted({row["m"] for row in rows})
    figure, axes = plt.subplots(1, len(m_values), figsize=(6.5 * len(m_values), 3.8), squeeze=False, sharey=True)
    for axis, m in zip(axes[0], m_values):
        chosen = [row for row in rows if row["m"] == m and row["test"] == test_kitchen]
        chosen.sort(key=lambda row: (row["situated"], len(row["train"]), row["train"]))
        parameters = list(chosen[0]["accuracy"])
        width = 0.8 / len(chosen)
        blues, reds = plt.cm.Blues, plt.cm.Reds
        n_out = sum(not row["situated"] for row in chosen)
        for index, row in enumerate(chosen):
            shade = 0.45 + 0.5 * ((index if not row["situated"] else index - n_out) + 1) / (len(chosen) + 1)
            colour = (reds if row["situated"] else blues)(shade)
            label = "+".join(k.replace("kitchen-", "K") for k in row["train"])
            positions = np.arange(len(parameters)) + (index - (len(chosen) - 1) / 2) * width
            axis.bar(positions, [row["accuracy"][p] for p in parameters], width, color=colour, label=label)
        axis.set_xticks(range(len(parameters)), parameters, fontsize=8)
        axis.set_title(f"serve-salad tested in {test_kitchen}, {m} demos per training kitchen")
        axis.set_ylim(0, 1.05)
        axis.grid(axis="y", alpha=0.3)
    axes[0][0].set_ylabel("accuracy")
    handles, labels = axes[0][0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8,
                  title="trained in (blue: without the test kitchen, red: with it)", title_fontsize=8)
    figure.tight_layout(rect=(0, 0.12, 1, 1))
    figure.savefig(path, dpi=110)
    plt.close(figure)


def markdown_cv(kitchen: str, per_parameter: dict[str, list[float]]) -> str:
    count = len(next(iter(per_parameter.values())))
    lines = [f"serve-pasta, {kitchen}: accuracy per parameter vs. training demonstrations m", "",
             "| parameter | " + " | ".join(f"m={m}" for m in range(1, count + 1)) + " |",
             "|---|" + "---:|" * count]
    lines += [f"| {name} | " + " | ".join(f"{v:.2f}" for v in values) + " |" for name, values in per_parameter.items()]
    return "\n".join(lines)


def markdown_transfer(rows: list[dict]) -> str:
    parameters = list(rows[0]["accuracy"])
    lines = ["| m | trained in | tested in | " + " | ".join(parameters) + " | mean |",
             "|---:|---|---|" + "---:|" * (len(parameters) + 1)]
    for row in rows:
        values = " | ".join(f"{row['accuracy'][p]:.2f}" for p in parameters)
        mark = "**" if row["situated"] else ""
        lines.append(f"| {row['m']} | {mark}{'+'.join(row['train'])}{mark} | {row['test']} | {values} | "
                     f"{row['mean']:.2f} |")
    return "\n".join(lines)


def available_kitchens(names: list[str]) -> list[str]:
    found = []
    for name in names:
        try:
            load_kitchen(name)
        except ValueError as error:
            print(f"skipping {name}: {error}", file=sys.stderr)
            continue
        found.append(name)
    return found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kitchens", nargs="+", default=list(DEFAULT_KITCHENS))
    parser.add_argument("--only", choices=("cv", "transfer"), default=None, help="run one experiment only")
    parser.add_argument("--cv-demos", type=int, default=12)
    parser.add_argument("--cv-repeats", type=int, default=12)
    parser.add_argument("--transfer-demos", type=int, default=6)
    parser.add_argument("--transfer-m", type=int, nargs="+", default=[2, 5])
    parser.add_argument("--transfer-repeats", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("docs/img"))
    parser.add_argument("--json", action="store_true", help="end with one JSON line of all numbers")
    args = parser.parse_args(argv)
    if args.cv_demos < 2 or args.transfer_demos < 2:
        parser.error("--cv-demos and --transfer-demos must be at least 2 (one to train, one to test)")
    if any(m < 1 or m >= args.transfer_demos for m in args.transfer_m):
        parser.error(f"--transfer-m values must lie in 1..{args.transfer_demos - 1}")
    kitchens = available_kitchens(args.kitchens)
    if not kitchens:
        parser.error("none of the --kitchens exists")
    args.out.mkdir(parents=True, exist_ok=True)
    # Small matrices: a multi-threaded BLAS only spins on a shared machine (150x slower measured).
    threadpool_limits(limits=1, user_api="blas")
    rng = np.random.default_rng(args.seed)
    started = time.perf_counter()
    summary: dict = {"seed": args.seed, "kitchens": kitchens}
    if args.only in (None, "cv"):
        pasta = load_builtin_recipe("serve-pasta")
        curves, variety = {}, {}
        for kitchen in kitchens:
            demos = collect(pasta, "serve-pasta", kitchen, args.cv_demos, args.seed)
            curves[kitchen] = cross_validation(pasta, demos, args.cv_repeats, rng)
            variety[kitchen] = varied_pairs(pasta, demos, rng)
            print(markdown_cv(kitchen, curves[kitchen]) + "\n", flush=True)
            print(f"m = 2, all {variety[kitchen]['pairs']} pairs: mean accuracy "
                  f"{variety[kitchen]['most_varied_accuracy']:.2f} for the most varied third (edit distance "
                  f"{variety[kitchen]['most_varied_distance_m']:.2f} m), "
                  f"{variety[kitchen]['least_varied_accuracy']:.2f} for the least varied third "
                  f"({variety[kitchen]['least_varied_distance_m']:.2f} m)\n", flush=True)
        plot_cross_validation(curves, recipe_parameters(pasta).objects, args.out / "recipe-cross-validation.png")
        summary["cross_validation"] = curves
        summary["pair_variety"] = variety
    if args.only in (None, "transfer"):
        if len(kitchens) < 2:
            print("transfer needs at least two kitchens; skipped", file=sys.stderr)
        else:
            salad = load_builtin_recipe("serve-salad")
            demos = {k: collect(salad, "serve-salad", k, args.transfer_demos, args.seed) for k in kitchens}
            rows = transfer(salad, demos, args.transfer_m, args.transfer_repeats, rng)
            print(markdown_transfer(rows) + "\n", flush=True)
            plot_transfer(rows, kitchens[0], args.out / "recipe-transfer.png")
            summary["transfer"] = rows
    summary["seconds"] = round(time.perf_counter() - started, 1)
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
