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
every random choice. The experiments live in ``dialog/experiments/recipes/study.py``
(also run, in parallel and with significance tests, by ``teachbot regress
--suite recipes``).

    python scripts/recipe_experiments.py --json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from bullet_world.catalogue import load_kitchen
from dialog.experiments.recipes.figures import markdown_cv, markdown_transfer, plot_cross_validation, plot_transfer
from dialog.experiments.recipes.study import collect, cross_validation, transfer, varied_pairs
from learning.recipes.format import load_builtin_recipe, recipe_parameters

DEFAULT_KITCHENS = ("kitchen-1", "kitchen-2", "kitchen-3")


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
