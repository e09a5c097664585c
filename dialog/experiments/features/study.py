"""The chapter-5 study: computational and human-driven feature selection with an RBF SVM.

For n = 12 and n = 100 training instances and k disjoint stratified random
samples (SRS), every approach picks a feature subset, an RBF SVM is trained on
it, and accuracy is measured on a held-out pool (thesis §5.3.2, §5.4.5,
table 5.2). Human teachers are simulated: each scripted "user" answers the
feature questions from the task's relevant features with its own small errors
(HFS: choose useful features; HFR: choose features to ignore), or shows three
representative examples per concept (HIS); HIS-FS and HIS-FR combine both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from bullet_world.datasets import Pool
from learning.errors import SettingsError
from learning.features.selection import select_features

COMPUTATIONAL = ("none", "FI", "ES", "ER")
HUMAN = ("HFS", "HFR", "HIS", "HIS-FS", "HIS-FR")
METHODS = COMPUTATIONAL + HUMAN


@dataclass(frozen=True)
class UserModel:
    """How a scripted teacher errs when it names features (probabilities per feature or group)."""

    keep_relevant: float = 0.9      # HFS: chance a relevant feature is chosen
    add_irrelevant: float = 0.03    # HFS: chance an irrelevant object feature is chosen too
    ignore_robot: float = 0.9       # HFR: chance a robot or environment feature is ignored
    ignore_irrelevant_object: float = 0.5  # HFR: chance an irrelevant object feature is ignored
    ignore_relevant: float = 0.05   # HFR: chance a relevant feature is ignored by mistake


def srs(concepts: np.ndarray, n: int, rng: np.random.Generator, exclude=()) -> np.ndarray:
    """Stratified random sample without replacement: n / |Y| rows of each concept."""
    labels = sorted(set(concepts.tolist()))
    per_class, extra = divmod(n, len(labels))
    excluded = set(np.asarray(exclude, dtype=int).tolist())
    rows = []
    for i, label in enumerate(labels):
        candidates = np.array([r for r in np.nonzero(concepts == label)[0] if r not in excluded])
        count = per_class + (1 if i < extra else 0)
        if len(candidates) < count:
            raise SettingsError(f"the pool has only {len(candidates)} free rows of '{label}', {count} needed")
        rows.extend(rng.choice(candidates, size=count, replace=False))
    return np.array(sorted(rows))


def hfs_answer(names, relevant: set[str], user: UserModel, rng: np.random.Generator) -> np.ndarray:
    """Features a scripted teacher chooses as useful (never empty)."""
    chosen = [i for i, name in enumerate(names)
              if (name in relevant and rng.random() < user.keep_relevant)
              or (name not in relevant and not _is_robot(name) and rng.random() < user.add_irrelevant)]
    return np.array(chosen or [i for i, name in enumerate(names) if name in relevant])


def hfr_answer(names, relevant: set[str], user: UserModel, rng: np.random.Generator) -> np.ndarray:
    """Features left after a scripted teacher names those to ignore (never empty)."""
    kept = []
    for i, name in enumerate(names):
        if name in relevant:
            ignore = rng.random() < user.ignore_relevant
        elif _is_robot(name):
            ignore = rng.random() < user.ignore_robot
        else:
            ignore = rng.random() < user.ignore_irrelevant_object
        if not ignore:
            kept.append(i)
    return np.array(kept or [i for i, name in enumerate(names) if name in relevant])


def his_examples(pool: Pool, rng: np.random.Generator, per_concept: int = 3) -> np.ndarray:
    """Three representative examples per concept: as many different kinds as possible (an apple, an orange...)."""
    rows = []
    for concept in sorted(set(pool.concepts.tolist())):
        members = np.nonzero(pool.concepts == concept)[0]
        kinds = sorted(set(pool.kinds[members].tolist()))
        order = [kinds[i] for i in rng.permutation(len(kinds))]
        for j in range(per_concept):
            kind = order[j % len(order)]
            candidates = [r for r in members if pool.kinds[r] == kind and r not in rows]
            rows.append(int(rng.choice(candidates)))
    return np.array(sorted(rows))


def _is_robot(name: str) -> bool:
    return name.startswith(("arm.", "hand.", "robot.", "environment."))


def svm_accuracy(train_X, train_y, test_X, test_y, features: np.ndarray) -> float:
    """RBF SVM on standardised selected features; accuracy on the test pool."""
    scaler = StandardScaler().fit(train_X[:, features])
    model = SVC(kernel="rbf", C=10.0, gamma="scale").fit(scaler.transform(train_X[:, features]), train_y)
    return float(np.mean(model.predict(scaler.transform(test_X[:, features])) == test_y))


def run_study(train: Pool, test: Pool, relevant: set[str], sizes=(12, 100), samples: int = 10,
              users: int = 10, user_model: UserModel = UserModel(), seed: int = 0, methods=METHODS) -> list[dict]:
    """Rows of (method, n, sample, user, accuracy, features) for every approach of table 5.2."""
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise SettingsError(f"unknown feature-selection approaches {unknown}; accepted: {', '.join(METHODS)}")
    names = train.feature_names
    rows = []
    root = np.random.SeedSequence(seed)
    sample_rng, user_rng = (np.random.default_rng(s) for s in root.spawn(2))
    teachers = [np.random.default_rng(s) for s in np.random.SeedSequence([seed, 1]).spawn(users)]
    answers = [{"HFS": hfs_answer(names, relevant, user_model, rng), "HFR": hfr_answer(names, relevant, user_model,
                rng), "HIS": his_examples(train, rng)} for rng in teachers]
    for n in sizes:
        used: list[int] = []
        draws = []
        for _ in range(samples):  # k disjoint SRS samples of size n
            sample = srs(train.concepts, n, sample_rng, exclude=used)
            used.extend(sample.tolist())
            draws.append(sample)
        for method in methods:
            for user_index, answer in enumerate(answers if method in HUMAN else [None]):
                for k, sample in enumerate(draws):
                    if method.startswith("HIS"):
                        if n <= len(answer["HIS"]):
                            if k > 0:
                                break  # with only the teacher's examples there is one training set per user
                            sample = answer["HIS"]
                        else:
                            top_up = srs(train.concepts, n - len(answer["HIS"]), user_rng, exclude=answer["HIS"])
                            sample = np.concatenate([answer["HIS"], top_up])
                    X, y = train.X[sample], train.concepts[sample]
                    if method in ("HFS", "HIS-FS"):
                        features = answer["HFS"]
                    elif method in ("HFR", "HIS-FR"):
                        features = answer["HFR"]
                    elif method == "HIS":
                        features = select_features(X, y, "ER")
                    else:
                        features = select_features(X, y, method)
                    rows.append({"method": method, "n": n, "sample": k, "user": user_index,
                                 "accuracy": svm_accuracy(X, y, test.X, test.concepts, features),
                                 "features": len(features)})
    return rows
