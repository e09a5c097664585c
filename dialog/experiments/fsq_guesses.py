"""The feature question's guessed answers against the teacher's (issue 49 item 3; ``learning.whatif.feature_guesses``).

On every turn the FSQ is still open and the training set holds an example, :class:`FeatureGuessProbe` records,
without changing the episode:

* for each guess of the teacher's answer, the predicted change of the learning features, E[phi_L(s') | FSQ] -
  phi_L(s), and of held-out accuracy, every answer refit exactly (``refit_probabilities``);
* the change the teacher's real answer (the task's relevant features, what the scripted teacher says with
  feature quality 1) would make, refit the same way: the "realised" change, the target every guess is judged by;
* with ``horizon``, the same guesses read over the examples the episode can still gather (the training set
  repeated to n + m examples, m the instance questions the budget and the clock still allow after the FSQ: the
  future examples assumed like the past ones) against the change the real answer makes on the episode's final
  training set, read on the same scene: what the answer is worth by the end, which one step does not see;
* every label and demonstration question's expected change of the learning features (the fast what-if of eq. 7.1),
  to count the states where one instance question is at least as good as the real answer on every learning
  feature: there no weights with the thesis's signs (every learning feature weighed >= 0, the FSQ's higher cost
  weighed <= 0) can prefer even a perfectly guessed FSQ.

Only the teacher's relevant features and the held-out pool are read beyond the learner's state; they are the
measurement, never an input of any guess.
"""

from __future__ import annotations

import numpy as np

from learning.decision.candidates import expected_decision_features
from learning.decision.features import LEARNING_FEATURES, concept_counts, learning_features
from learning.evaluation import most_probable_accuracy
from learning.whatif.feature_guesses import GUESSES, guessed_answers, refit_probabilities

K = len(LEARNING_FEATURES)


def answer_effect(state, answers, test_X, test_y, training=None, scene=None, scaler=None) -> tuple[np.ndarray, float]:
    """E[(phi_L, held-out accuracy)] over ``answers`` (probability, subsets), each refit exactly on ``training``
    (default the state's) and read on ``scene`` (default the state's); with no answer, the current features'."""
    X, labels = state.training_matrix() if training is None else training
    scene = state.scene_X if scene is None else scene
    if not answers:
        answers = [(1.0, dict(state.fitted_feature_subsets))]
    rows = np.vstack([scene, test_X])
    counts, n = np.array([sum(label == c for label in labels) for c in state.concepts], dtype=float), len(scene)
    phi, acc = np.zeros(K), 0.0
    for probability, subsets in answers:
        P = refit_probabilities(state, subsets, rows, (X, labels), scaler)
        phi += probability * learning_features(P[:n], counts)[:K]
        acc += probability * most_probable_accuracy(P[n:], state.concepts, test_y)
    return phi, acc


def examples_still_affordable(state) -> int:
    """m: the label or demonstration questions the budget and the clock still allow once the FSQ is paid."""
    progress = state.progress
    cheapest = min(progress.costs["label"], progress.costs["demo"])
    left = progress.remaining_budget - progress.costs["feature"]
    return int(max(0, min(progress.turns - progress.turn - 1, left // cheapest if cheapest > 0 else left)))


class FeatureGuessProbe:
    """A manager observer: one record per decision with the FSQ open and an example learned (module docstring)."""

    def __init__(self, relevant_features, guesses=GUESSES, horizon: bool = False):
        self.relevant, self.guesses, self.horizon = tuple(relevant_features), tuple(guesses), horizon
        self.manager = None
        self.records: list[dict] = []
        self._views: list[tuple] = []  # (scene, scaler, current subsets) of every record, for ``finish``

    def attach(self, manager) -> None:
        self.manager = manager

    def on_decision(self, decision) -> None:
        state = self.manager.state
        if state.feature_query_asked or len(state.training_matrix()[0]) == 0:
            return
        test_X, test_y = self.manager._test  # the held-out pool the manager scores (drawn once, read here)
        phi = learning_features(state.probabilities(), concept_counts(state))[:K]
        acc = most_probable_accuracy(state.probabilities(test_X), state.concepts, test_y)
        real_phi, real_acc = answer_effect(state, self._teacher_answer(state), test_X, test_y)
        record = {"turn": self.manager.turn + 1, "examples": len(state.training_matrix()[0]),
                  "action": decision.action.kind, "phi": phi.tolist(), "accuracy": acc,
                  "realised": (real_phi - phi).tolist(), "realised_accuracy": real_acc - acc, "guesses": {}}
        for guess in self.guesses:
            guess_phi, guess_acc = answer_effect(state, guessed_answers(state, guess), test_X, test_y)
            record["guesses"][guess] = {"predicted": (guess_phi - phi).tolist(), "predicted_accuracy": guess_acc - acc}
        if self.horizon:
            self._horizon(state, record, test_X, test_y)
        table = expected_decision_features(state)
        instance = [i for i, a in enumerate(table.actions) if a.kind in ("label", "demo")]
        record["instance"] = (table.expected[instance, :K] - phi).tolist()
        self.records.append(record)

    def on_turn(self, record: dict, scene) -> None:
        pass

    def _teacher_answer(self, state) -> list[tuple]:
        """The teacher's real answer as the one certain answer: every classifier on the task's relevant features."""
        names = list(state.feature_names)
        relevant = np.array(sorted(names.index(name) for name in self.relevant))
        return [(1.0, {c: relevant for c in state.concepts})]

    def _horizon(self, state, record, test_X, test_y) -> None:
        X, labels = state.training_matrix()
        m = examples_still_affordable(state)
        copies = max(1, int(round((len(X) + m) / len(X))))
        evidence = (np.repeat(X, copies, axis=0), [label for label in labels for _ in range(copies)])
        base_phi, base_acc = answer_effect(state, [], test_X, test_y, evidence)
        record["horizon"] = {"m": m, "copies": copies}
        for guess in self.guesses:
            phi, acc = answer_effect(state, guessed_answers(state, guess), test_X, test_y, evidence)
            record["guesses"][guess]["horizon"] = (phi - base_phi).tolist()
            record["guesses"][guess]["horizon_accuracy"] = acc - base_acc
        self._views.append((record, state.scene_X, state.scaler, dict(state.fitted_feature_subsets)))

    def finish(self, state) -> list[dict]:
        """With ``horizon``: the real answer's change on the final training set, read on each record's scene."""
        test_X, test_y = self.manager._test
        final, teacher = state.training_matrix(), self._teacher_answer(state)
        for record, scene, scaler, current in self._views:
            phi0, acc0 = answer_effect(state, [(1.0, current)], test_X, test_y, final, scene, scaler)
            phi1, acc1 = answer_effect(state, teacher, test_X, test_y, final, scene, scaler)
            record["realised_by_end"], record["realised_accuracy_by_end"] = (phi1 - phi0).tolist(), acc1 - acc0
        return self.records


def dominated(record: dict, predicted: list[float] | None = None) -> bool:
    """One label or demonstration question expected at least as good on every learning feature as the FSQ's
    change (the teacher's real one unless ``predicted`` is given)."""
    fsq = np.array(record["realised"] if predicted is None else predicted)
    instance = np.array(record["instance"])
    return bool(len(instance) and (instance >= fsq - 1e-12).all(axis=1).any())


TARGETS = ("classifier_discriminability", "instance_variation", "prediction_margin", "accuracy")


def guess_table(records: list[dict], guesses=GUESSES) -> list[dict]:
    """Per guess and target: n, mean predicted, mean realised, Pearson r (None when a side is constant), mean
    absolute error; and per guess the states where its own prediction is dominated."""
    rows = []
    for guess in guesses:
        for target in TARGETS:
            if target == "accuracy":
                p = np.array([r["guesses"][guess]["predicted_accuracy"] for r in records])
                q = np.array([r["realised_accuracy"] for r in records])
            else:
                j = LEARNING_FEATURES.index(target)
                p = np.array([r["guesses"][guess]["predicted"][j] for r in records])
                q = np.array([r["realised"][j] for r in records])
            r = float(np.corrcoef(p, q)[0, 1]) if len(p) > 1 and p.std() > 0 and q.std() > 0 else None
            rows.append({"guess": guess, "target": target, "n": len(p), "predicted": float(p.mean()),
                         "realised": float(q.mean()), "correlation": r, "mae": float(np.abs(p - q).mean())})
    return rows


EXAMPLE_GROUPS = ((1, 2), (3, 5), (6, 10), (11, 20), (21, None))


def by_examples(records: list[dict]) -> list[dict]:
    """The real answer's mean one-step change (ACD, held-out accuracy) beside the best label or demonstration
    question's predicted ACD change, with the states grouped by how many examples the learner holds."""
    rows = []
    for low, high in EXAMPLE_GROUPS:
        mine = [r for r in records if r["examples"] >= low and (high is None or r["examples"] <= high)]
        if not mine:
            continue
        best = [max(q[0] for q in r["instance"]) for r in mine if r["instance"]]
        rows.append({"examples": f"{low}-{high}" if high else f"{low}+", "states": len(mine),
                     "real_acd": float(np.mean([r["realised"][0] for r in mine])),
                     "real_accuracy": float(np.mean([r["realised_accuracy"] for r in mine])),
                     "best_instance_acd": float(np.mean(best)) if best else None})
    return rows


def horizon_table(records: list[dict], guesses=GUESSES) -> list[dict]:
    """Per guess, reading (one step, or over the examples still to come) and target (ACD, accuracy): the mean
    prediction against the real answer's change by the end of the episode, r, mean absolute error; all turns and
    turns 1-5."""
    rows = []
    for guess in guesses:
        for reading, key in (("one step", "predicted"), ("horizon", "horizon")):
            for target in ("classifier_discriminability", "accuracy"):
                for turns, mine in (("all", records), ("1-5", [r for r in records if r["turn"] <= 5])):
                    if not mine:
                        continue
                    if target == "accuracy":
                        p = np.array([r["guesses"][guess][f"{key}_accuracy"] for r in mine])
                        q = np.array([r["realised_accuracy_by_end"] for r in mine])
                    else:
                        p = np.array([r["guesses"][guess][key][0] for r in mine])
                        q = np.array([r["realised_by_end"][0] for r in mine])
                    r = float(np.corrcoef(p, q)[0, 1]) if len(p) > 1 and p.std() > 0 and q.std() > 0 else None
                    rows.append({"guess": guess, "reading": reading, "target": target, "turns": turns, "n": len(p),
                                 "predicted": float(p.mean()), "realised": float(q.mean()), "correlation": r,
                                 "mae": float(np.abs(p - q).mean())})
    return rows
