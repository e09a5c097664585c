"""teachbot's questioning against scikit-activeml's and modAL's on the same pools, with the same oracle teacher.

Data: scikit-learn's bundled iris, wine, breast-cancer and digits sets (nobody here wrote them). Each repeat
splits a data set into a pool and a held-out test set (stratified, seeded), then draws the same
sequence of scenes for every method: ``--objects`` pool rows, a new scene every ``--change-every``
turns, ``--turns`` turns, ``--budget`` cost units (label 1, demonstration 2, feature query 2).

Methods:
- ``teachbot-dt``: TeachingLoop(strategy="dt-task"), the decision-theoretic choice among label,
  demonstration, feature and no query. The oracle labels objects, demonstrates a scene object of the
  asked concept (None if the scene has none) and skips the feature query (it knows no feature truth).
- ``teachbot-entropy``: TeachingLoop(strategy="active"), entropy sampling with label queries only.
- ``teachbot-dt-labels``: the same DT with only label queries priced, as the peers have (a demonstration
  or the feature query costs more than the whole budget, so never a candidate): label queries or none.
- ``teachbot-voi`` and ``teachbot-voi-labels``: the same two settings with ``dt-voi`` (issue 40: the query
  whose expected gain in objects right beats its price from the allocation, else none).
- ``skactiveml-us``: UncertaintySampling(method="entropy"), and ``skactiveml-eer``: MonteCarloEER
  (misclassification loss), both on scikit-learn's GaussianProcessClassifier with teachbot's fixed kernel
  (4.0 * RBF(sqrt |F|), no optimiser) on pool-standardised features; one label query per turn while the
  budget lasts, among the scene objects not yet labelled in this scene.
- ``modal-entropy``: modAL's ActiveLearner with entropy_sampling on the same classifier, the same turns
  (modAL 0.4.2.1's expected_error module does not import under numpy 2, so it has no EER row, and its
  ``fit`` fails under scikit-learn 1.9, so the estimator is fitted directly; modAL chooses). With fewer
  than two classes labelled the classifier gives uniform probabilities (modAL then takes the first
  candidate), as skactiveml's wrapper does.

Comparable rows: the label-only ones ask the same kind of question at the same price: teachbot-entropy,
skactiveml-us and modal-entropy (entropy sampling, a label every turn the budget allows); teachbot-dt-labels,
teachbot-voi-labels and skactiveml-eer (expected-utility or expected-error choices among labels; DT and dt-voi
may also stay quiet). teachbot-dt and teachbot-voi are not comparable in accuracy: they may also buy
demonstrations (cost 2) and ask a feature query.

Timing: CPU time of this process (the machine is shared; other programs do not inflate it); one decision
is ``TeachingLoop.ask()`` or ``query()``; refitting after an answer is outside it
(``tell`` for teachbot; for UncertaintySampling the classifier is fitted after each label and ``query``
gets ``fit_clf=False``). MonteCarloEER must fit inside ``query`` (it refits per candidate and answer on
the labelled rows it is given), so its time holds one extra fit on those few labels.
Turns with the budget spent are not timed. Accuracy is on the test set after the last turn.
Needs the ``peers`` extra (``pip install -e .[peers]``: scikit-activeml and modAL-python).

    python scripts/bench_peers.py --json          # last line: one JSON object
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from sklearn.datasets import load_breast_cancer, load_digits, load_iris, load_wine  # noqa: E402
from sklearn.gaussian_process import GaussianProcessClassifier  # noqa: E402
from sklearn.gaussian_process.kernels import RBF, ConstantKernel  # noqa: E402
from sklearn.model_selection import train_test_split  # noqa: E402

from learning import TeachingLoop  # noqa: E402

DATASETS = {"iris": load_iris, "wine": load_wine, "breast-cancer": load_breast_cancer, "digits": load_digits}
METHODS = ("teachbot-dt", "teachbot-dt-labels", "teachbot-voi", "teachbot-voi-labels", "teachbot-entropy",
           "skactiveml-us", "skactiveml-eer", "modal-entropy")
TEACHBOT_STRATEGIES = {"teachbot-dt": "dt-task", "teachbot-dt-labels": "dt-task", "teachbot-voi": "dt-voi",
                       "teachbot-voi-labels": "dt-voi", "teachbot-entropy": "active"}
LABELS_ONLY = ("teachbot-dt-labels", "teachbot-voi-labels")
COMPARABLE = {"teachbot-dt": "not comparable (demonstrations and the feature query too)",
              "teachbot-dt-labels": "labels only: vs skactiveml-eer",
              "teachbot-voi": "not comparable (demonstrations and the feature query too)",
              "teachbot-voi-labels": "labels only: vs skactiveml-eer and the entropy rows",
              "skactiveml-eer": "labels only: vs teachbot-dt-labels, teachbot-voi-labels",
              "teachbot-entropy": "entropy, labels only", "skactiveml-us": "entropy, labels only",
              "modal-entropy": "entropy, labels only"}
RATIOS = (("teachbot-dt", "skactiveml-eer"), ("teachbot-dt-labels", "skactiveml-eer"),
          ("teachbot-voi-labels", "skactiveml-eer"), ("teachbot-voi-labels", "teachbot-entropy"),
          ("teachbot-entropy", "skactiveml-us"), ("teachbot-entropy", "modal-entropy"))


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--datasets", nargs="+", default=list(DATASETS), choices=sorted(DATASETS))
    parser.add_argument("--repeats", type=int, default=5, help="seeded pool/test splits per data set (default 5)")
    parser.add_argument("--turns", type=int, default=30)
    parser.add_argument("--budget", type=float, default=20.0)
    parser.add_argument("--objects", type=int, default=12, help="pool rows per scene (default 12)")
    parser.add_argument("--change-every", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    for name in ("repeats", "turns", "objects", "change_every"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be at least 1, got {getattr(args, name)}")
    return args


def scenes_for(pool_size: int, args, rng: np.random.Generator) -> list[np.ndarray]:
    """Pool indices of each scene, the same for every method."""
    count = -(-args.turns // args.change_every)
    return [rng.choice(pool_size, min(args.objects, pool_size), replace=False) for _ in range(count)]


def run_teachbot(method: str, X, y, scenes, X_test, y_test, args, seed: int) -> dict:
    costs = None  # teachbot's own: label 1, demonstration 2, feature query 2
    if method in LABELS_ONLY:  # only labels priced: anything else costs more than the whole budget
        costs = {"label": 1, "demo": args.budget + 1, "feature": args.budget + 1}
    loop = TeachingLoop(np.unique(y), strategy=TEACHBOT_STRATEGIES[method], budget=args.budget, turns=args.turns,
                        change_every=args.change_every, costs=costs, seed=seed)
    times, index = [], None
    for turn in range(args.turns):
        if turn % args.change_every == 0:
            index = scenes[turn // args.change_every]
            loop.observe(X[index])
        can_ask = loop.budget_left >= min(loop.costs[k] for k in ("label", "demo", "feature"))
        start = time.process_time()
        query = loop.ask()
        if can_ask:  # turns with the budget spent are no decisions (the peers time none either)
            times.append(time.process_time() - start)
        truth = y[index]
        if query.kind == "label":
            loop.tell(truth[query.object])
        elif query.kind == "demo":
            members = np.flatnonzero(truth == query.concept)
            loop.tell(int(members[0]) if len(members) else None)
        else:
            loop.tell(None)
    kinds = [t.query.kind for t in loop.history]
    return {"accuracy": float(np.mean(loop.predict(X_test) == y_test)), "times": times,
            "queries": {k: kinds.count(k) for k in ("label", "demo", "feature", "none")}}


class UnweightedGPClassifier(GaussianProcessClassifier):
    """scikit-learn's GP classifier with the ``sample_weight`` argument MonteCarloEER passes (only unit weights)."""

    def fit(self, X, y, sample_weight=None):
        if sample_weight is not None and not np.allclose(sample_weight, 1.0):
            raise ValueError("GaussianProcessClassifier takes no sample weights other than 1")
        return super().fit(X, y)


def peer_classifier(classes, n_features: int, seed: int):
    from skactiveml.classifier import SklearnClassifier

    kernel = ConstantKernel(4.0, "fixed") * RBF(np.sqrt(n_features), "fixed")
    return SklearnClassifier(UnweightedGPClassifier(kernel=kernel, optimizer=None), classes=classes,
                             missing_label=-1, random_state=seed)


def run_peer(method: str, X, y, scenes, X_test, y_test, args, seed: int) -> dict:
    from skactiveml.pool import MonteCarloEER, UncertaintySampling

    mean, std = X.mean(axis=0), np.where(X.std(axis=0) > 0, X.std(axis=0), 1.0)
    Xs, Xs_test = (X - mean) / std, (X_test - mean) / std
    classes = np.unique(y)
    chooser = UncertaintySampling(method="entropy", missing_label=-1, random_state=seed) \
        if method == "skactiveml-us" else MonteCarloEER(missing_label=-1, random_state=seed)
    clf = peer_classifier(classes, X.shape[1], seed)
    labelled_X, labelled_y = np.zeros((0, X.shape[1])), np.zeros(0, dtype=int)
    clf.fit(labelled_X, labelled_y)
    budget, times, asked = args.budget, [], set()
    for turn in range(args.turns):
        index = scenes[turn // args.change_every]
        if turn % args.change_every == 0:
            asked = set()
        candidates = [i for i in range(len(index)) if i not in asked]
        if budget < 1 or not candidates:
            continue
        X_all = np.vstack([labelled_X, Xs[index]])
        y_all = np.concatenate([labelled_y, np.full(len(index), -1)])
        start = time.process_time()
        chosen = chooser.query(X_all, y_all, clf, fit_clf=method == "skactiveml-eer",
                               candidates=np.array(candidates) + len(labelled_X))
        times.append(time.process_time() - start)
        pick = int(chosen[0]) - len(labelled_X)
        asked.add(pick)
        budget -= 1
        labelled_X = np.vstack([labelled_X, Xs[index[pick]]])
        labelled_y = np.append(labelled_y, y[index[pick]])
        clf.fit(labelled_X, labelled_y)
    labels = int(len(labelled_y))
    return {"accuracy": float(np.mean(clf.predict(Xs_test) == y_test)), "times": times,
            "queries": {"label": labels, "demo": 0, "feature": 0, "none": args.turns - labels}}


class UniformUntilTwoClasses(GaussianProcessClassifier):
    """scikit-learn's GP classifier that predicts uniform probabilities over ``classes`` until two are labelled
    (it cannot fit one class); what skactiveml's wrapper does for its peers, here for modAL."""

    def __init__(self, classes=None, kernel=None, optimizer=None):
        super().__init__(kernel=kernel, optimizer=optimizer)
        self.classes = classes

    def fit(self, X, y):
        self.seen_ = np.unique(y)
        if len(self.seen_) >= 2:
            super().fit(X, y)
        return self

    def predict_proba(self, X):
        probabilities = np.full((len(X), len(self.classes)), 1.0 / len(self.classes))
        if len(getattr(self, "seen_", ())) >= 2:
            probabilities[:] = 0.0
            probabilities[:, np.searchsorted(self.classes, self.seen_)] = super().predict_proba(X)
        return probabilities

    def predict(self, X):
        return np.asarray(self.classes)[np.argmax(self.predict_proba(X), axis=1)]


def run_modal(method: str, X, y, scenes, X_test, y_test, args, seed: int) -> dict:
    """modAL's ActiveLearner with entropy sampling, one label per turn among the scene's unasked objects."""
    from modAL.models import ActiveLearner
    from modAL.uncertainty import entropy_sampling

    mean, std = X.mean(axis=0), np.where(X.std(axis=0) > 0, X.std(axis=0), 1.0)
    Xs, Xs_test = (X - mean) / std, (X_test - mean) / std
    kernel = ConstantKernel(4.0, "fixed") * RBF(np.sqrt(X.shape[1]), "fixed")
    learner = ActiveLearner(estimator=UniformUntilTwoClasses(np.unique(y), kernel), query_strategy=entropy_sampling)
    labelled_X, labelled_y = np.zeros((0, X.shape[1])), np.zeros(0, dtype=y.dtype)
    budget, times, asked = args.budget, [], set()
    for turn in range(args.turns):
        index = scenes[turn // args.change_every]
        if turn % args.change_every == 0:
            asked = set()
        candidates = [i for i in range(len(index)) if i not in asked]
        if budget < 1 or not candidates:
            continue
        start = time.process_time()
        chosen, _ = learner.query(Xs[index[candidates]])
        times.append(time.process_time() - start)
        pick = candidates[int(np.ravel(chosen)[0])]
        asked.add(pick)
        budget -= 1
        labelled_X = np.vstack([labelled_X, Xs[index[pick]]])
        labelled_y = np.append(labelled_y, y[index[pick]])
        # refit outside the timed decision, as for the other peers; on the estimator itself: modAL 0.4.2.1's
        # fit passes check_X_y an argument scikit-learn 1.9 no longer has
        learner.estimator.fit(labelled_X, labelled_y)
    labels = int(len(labelled_y))
    return {"accuracy": float(np.mean(learner.predict(Xs_test) == y_test)), "times": times,
            "queries": {"label": labels, "demo": 0, "feature": 0, "none": args.turns - labels}}


def summarise(runs: list[dict]) -> dict:
    times = np.array([t for run in runs for t in run["times"]]) * 1000.0
    accuracies = [run["accuracy"] for run in runs]
    queries = {k: float(np.mean([run["queries"][k] for run in runs])) for k in ("label", "demo", "feature", "none")}
    return {"accuracy_mean": round(float(np.mean(accuracies)), 4), "accuracy_std": round(float(np.std(accuracies)), 4),
            "decision_p50_ms": round(float(np.percentile(times, 50)), 3),
            "decision_p95_ms": round(float(np.percentile(times, 95)), 3), "queries_mean": queries}


def benchmark(args) -> dict:
    results = {}
    for name in args.datasets:
        X_all, y_all = DATASETS[name](return_X_y=True)
        runs = {method: [] for method in METHODS}
        for repeat in range(args.repeats):
            seed = args.seed + repeat
            X, X_test, y, y_test = train_test_split(X_all, y_all, test_size=0.3, stratify=y_all, random_state=seed)
            scenes = scenes_for(len(y), args, np.random.default_rng(seed))
            for method in METHODS:
                run = run_teachbot if method.startswith("teachbot") else \
                    run_modal if method.startswith("modal") else run_peer
                runs[method].append(run(method, X, y, scenes, X_test, y_test, args, seed))
        summary = {method: summarise(r) for method, r in runs.items()}
        summary["ratios"] = {f"{a}/{b}": {
            "p50": round(summary[a]["decision_p50_ms"] / max(summary[b]["decision_p50_ms"], 1e-9), 3),
            "p95": round(summary[a]["decision_p95_ms"] / max(summary[b]["decision_p95_ms"], 1e-9), 3),
            "accuracy": round(summary[a]["accuracy_mean"] - summary[b]["accuracy_mean"], 4)} for a, b in RATIOS}
        results[name] = summary
    return {"settings": {k: getattr(args, k) for k in ("repeats", "turns", "budget", "objects", "change_every",
                                                        "seed")}, "comparable": COMPARABLE, "results": results}


def main(argv=None) -> int:
    args = _parse(sys.argv[1:] if argv is None else argv)
    try:
        import modAL  # noqa: F401
        import skactiveml  # noqa: F401
    except ImportError as missing:
        print(f"bench_peers: {missing.name} is not installed; pip install -e .[peers]", file=sys.stderr)
        return 2
    # skactiveml warns each time its GP sees one class only and falls back to class counts, as designed
    warnings.filterwarnings("ignore", category=UserWarning, module="skactiveml")
    report = benchmark(args)
    for name, summary in report["results"].items():
        print(f"{name}: accuracy mean (std), decision p50 / p95 ms, mean queries label/demo/feature/none")
        for method in METHODS:
            s, q = summary[method], summary[method]["queries_mean"]
            print(f"  {method:18s} {s['accuracy_mean']:.3f} ({s['accuracy_std']:.3f})  "
                  f"{s['decision_p50_ms']:8.2f} / {s['decision_p95_ms']:8.2f}  "
                  f"{q['label']:.1f}/{q['demo']:.1f}/{q['feature']:.1f}/{q['none']:.1f}  {COMPARABLE[method]}")
        for pair, ratio in summary["ratios"].items():
            print(f"  {pair}: time p50 x{ratio['p50']}, p95 x{ratio['p95']}, accuracy {ratio['accuracy']:+.3f}")
    if args.json:
        print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
