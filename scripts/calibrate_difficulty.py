"""How hard is a task's concept-learning problem? (thesis §5.3.2, Figure 5.2; §6.5.1)

Trains a classifier on n = 12 and n = 100 stratified instances from the task's
cached training pools (k disjoint samples, each pool giving k / pools of them)
and measures accuracy on the held-out test pool, with four feature sets:

* all:         every feature the robot senses (object, room, robot)
* informative: the task's ``relevant_features`` (what a good teacher names)
* ER:          backward elimination on the CFS merit, chosen from the sample
* irrelevant:  everything else (should be near chance)

The problem is calibrated when all features are clearly worse than the
informative ones with 12 instances, the informative ones reach high accuracy
with 100, and neither extreme is trivial (100%) or hopeless (chance).
The classifier is an RBF SVM (the thesis's, §5.3.1) or a GP (``--classifier gp``).

    .venv/bin/python scripts/calibrate_difficulty.py --json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.stats import mannwhitneyu
from sklearn.gaussian_process import GaussianProcessClassifier
from sklearn.gaussian_process.kernels import RBF, ConstantKernel
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bullet_world.catalogue import load_task  # noqa: E402
from bullet_world.datasets import load_datasets  # noqa: E402
from learning.features.selection import select_features  # noqa: E402

FEATURE_SETS = ("all", "informative", "ER", "irrelevant")


def classifier(kind: str):
    if kind == "gp":
        return make_pipeline(StandardScaler(), GaussianProcessClassifier(ConstantKernel(1.0) * RBF(3.0),
                                                                         random_state=0))
    return make_pipeline(StandardScaler(), SVC(kernel="rbf", C=1.0, gamma="scale"))


def training_samples(pools, n: int, k: int, concepts, seed: int) -> list[np.ndarray]:
    """k disjoint stratified samples of n rows: (pool index, row indices) spread over the pools."""
    samples = []
    per_class = n // len(concepts)
    for i in range(k):
        pool_index = i % len(pools)
        chunk = i // len(pools)
        rng = np.random.default_rng([seed, pool_index])
        rows = []
        for concept in concepts:
            candidates = rng.permutation(np.flatnonzero(pools[pool_index].concepts == concept))
            start = chunk * per_class
            if start + per_class > len(candidates):
                raise ValueError(f"pool {pool_index} is too small for {k} disjoint samples of {n}")
            rows.append(candidates[start:start + per_class])
        samples.append((pool_index, np.concatenate(rows)))
    return samples


def columns_for(feature_set: str, names, relevant, X, y) -> np.ndarray:
    if feature_set == "all":
        return np.arange(len(names))
    if feature_set == "informative":
        return np.array([names.index(f) for f in relevant])
    if feature_set == "irrelevant":
        return np.array([i for i, f in enumerate(names) if f not in relevant])
    return np.asarray(select_features(X, y, "ER"))


def evaluate(datasets, relevant, n: int, k: int, kind: str, seed: int) -> dict[str, list[float]]:
    names = list(datasets.feature_names)
    concepts = sorted(set(datasets.test.concepts.tolist()))
    scores = {name: [] for name in FEATURE_SETS}
    for pool_index, rows in training_samples(datasets.train, n, k, concepts, seed):
        X, y = datasets.train[pool_index].X[rows], datasets.train[pool_index].concepts[rows]
        for feature_set in FEATURE_SETS:
            columns = columns_for(feature_set, names, relevant, X, y)
            model = classifier(kind).fit(X[:, columns], y)
            predicted = model.predict(datasets.test.X[:, columns])
            scores[feature_set].append(float(np.mean(predicted == datasets.test.concepts)))
    return scores


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", default="pack-lunchbox")
    parser.add_argument("--kitchen", default="kitchen-1")
    parser.add_argument("--sizes", type=int, nargs="+", default=[12, 100], help="training-set sizes n")
    parser.add_argument("--samples", type=int, default=10, help="k disjoint training samples per size")
    parser.add_argument("--classifier", choices=("svm", "gp"), default="svm")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cache", default=None, help="cache folder (default ~/.cache/teachbot or $TEACHBOT_CACHE)")
    parser.add_argument("--no-robot", action="store_true", help="data sets without the arm's features")
    parser.add_argument("--rebuild", action="store_true", help="render the data sets again")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    warnings.filterwarnings("ignore", module="sklearn.gaussian_process")  # length scales at their bounds

    robot_factory = None
    if not args.no_robot:
        from robot import Arm

        robot_factory = Arm
    started = time.perf_counter()
    datasets = load_datasets(args.task, args.kitchen, robot_factory=robot_factory, cache=args.cache,
                             rebuild=args.rebuild, progress=lambda m: print(m, file=sys.stderr, flush=True))
    relevant = load_task(args.task).relevant_features
    chance = 1.0 / len(set(datasets.test.concepts.tolist()))
    print(f"{args.task} in {args.kitchen}: {len(datasets.feature_names)} features, {len(relevant)} informative; "
          f"test pool {len(datasets.test)}; classifier {args.classifier}; k = {args.samples}; chance {chance:.2f}")
    print(f"{'n':>4} | " + " | ".join(f"{name:>16}" for name in FEATURE_SETS) + " | all < informative (p)")
    table = {}
    for n in args.sizes:
        try:
            scores = evaluate(datasets, relevant, n, args.samples, args.classifier, args.seed)
        except ValueError as error:
            print(f"calibrate_difficulty: n = {n}: {error}; use smaller --sizes or fewer --samples",
                  file=sys.stderr)
            return 2
        p_value = float(mannwhitneyu(scores["all"], scores["informative"], alternative="less").pvalue)
        cells = " | ".join(f"{np.mean(scores[s]):.3f} +- {np.std(scores[s]):.3f}".rjust(16) for s in FEATURE_SETS)
        print(f"{n:>4} | {cells} | {p_value:.2g}")
        table[str(n)] = {name: {"mean": round(float(np.mean(v)), 4), "std": round(float(np.std(v)), 4)}
                         for name, v in scores.items()} | {"p_all_below_informative": p_value}
    if args.json:
        print(json.dumps({"task": args.task, "kitchen": args.kitchen, "classifier": args.classifier,
                          "samples": args.samples, "features": len(datasets.feature_names),
                          "informative": len(relevant), "chance": chance, "accuracy": table,
                          "seconds": round(time.perf_counter() - started, 1)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
