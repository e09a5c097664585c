"""What-if calibration (issue 49 item 2): the one-step what-if's predictions against what the answer did.

Eq. 7.1 ranks a query a by E[phi(s') | a] (``learning.decision.candidates``, eq. 6.3): the fast engine's
simulated answers, weighted by the learner's own p(y|x). For every question a DT strategy asks in a real
episode (the dialog manager, a scripted teacher, cached pools), :class:`WhatIfRecorder` keeps

* the predicted change of every learning feature, E[phi_L(s') | a] - phi_L(s), as the strategy saw it,
  and the realised change phi_L(s_after) - phi_L(s) after the teacher's actual answer, on the same scene;
* the predicted change of held-out accuracy: the same what-if with the test pool's rows joined to the scene
  (``learning.whatif.fast.pair_table`` / ``feature_outcomes`` with ``extra``), each simulated answer's
  accuracy weighted as eq. 6.3 weighs it, minus the accuracy now; and the realised change at the turn and by
  the end of the allocation (the latter is what the decision should value; later turns' questions add to it);
* for the alternatives it did not take, the mean predicted change per kind (no answer is realised for them).

The recorder only reads: the strategy's last candidates table, the state's probabilities and counts, and
the test pool. It never touches a random generator, so the episode asks the same questions with it or
without it (``tests/dialog/test_whatif_calibration.py``; the fingerprint test covers the episodes).
"""

from __future__ import annotations

import tempfile
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from dialog.episode import build_episode, embodied_timing
from dialog.experiments.episodes import EpisodeSpec, suite_teacher
from dialog.experiments.irl_rollouts import training_condition
from dialog.experiments.pools import PoolEnvironment, load_pools
from dialog.manager import episode_generators
from dialog.threads import one_blas_thread
from dialog.transcripts.jsonl import TranscriptWriter
from learning.actions import DemoQuery, LabelQuery
from learning.decision.features import LEARNING_FEATURES, concept_counts, label_distribution, learning_features
from learning.evaluation import most_probable_accuracy
from learning.whatif.fast import feature_outcomes, pair_table

KINDS = ("label", "demo", "feature")


def predicted_accuracy(state, action, test_X: np.ndarray, test_y: np.ndarray) -> float:
    """E[accuracy on the test pool after a] under the fast what-if (eq. 6.3's weights over the answers)."""
    n, concepts = len(state.scene_X), state.concepts
    P = state.probabilities()
    if isinstance(action, LabelQuery):  # the teacher names concept y with p(y|x) normalised over the concepts
        table = pair_table(state, test_X)[action.object_index]  # [y, i, c]
        weights = label_distribution(P)[action.object_index]
        return float(sum(w * most_probable_accuracy(table[y, n:], concepts, test_y) for y, w in enumerate(weights)))
    if isinstance(action, DemoQuery):  # the teacher shows object x with p(x|y) normalised over the scene
        y = concepts.index(action.concept)
        column = P[:, y]
        weights = column / column.sum() if column.sum() > 0 else np.full(n, 1.0 / n)
        table = pair_table(state, test_X)[:n, y]  # [x, i, c]
        return float(sum(w * most_probable_accuracy(table[x, n:], concepts, test_y) for x, w in enumerate(weights)))
    outcome = feature_outcomes(state, test_X)  # the FSQ: each answer F_{y,c} with probability 1/|Y|
    return float(np.mean([most_probable_accuracy(outcome[y, n:], concepts, test_y) for y in range(len(concepts))]))


class WhatIfRecorder:
    """A manager observer: one record per question asked (module docstring); ``attach`` it to the manager."""

    def __init__(self, strategy, accuracy_what_if: bool = True):
        self.strategy, self.accuracy_what_if = strategy, accuracy_what_if
        self.manager = None
        self.records: list[dict] = []
        self.quiet_turns = 0
        self._pending: dict | None = None

    def attach(self, manager) -> None:
        self.manager = manager

    def on_decision(self, decision) -> None:
        candidates, state = self.strategy.last_candidates, self.manager.state
        self._pending = None
        if decision.action.kind == "none" or candidates is None or decision.action not in candidates.actions:
            return
        k = len(LEARNING_FEATURES)
        index = candidates.actions.index(decision.action)
        before = learning_features(state.probabilities(), concept_counts(state))
        predicted = candidates.expected[:, :k] - candidates.current[:k]
        alternatives = {kind: predicted[[i for i, a in enumerate(candidates.actions) if a.kind == kind
                                         and i != index]].mean(axis=0).tolist()
                        for kind in KINDS if sum(a.kind == kind for i, a in enumerate(candidates.actions)
                                                 if i != index)}
        accuracy_now = self.manager.test_accuracy()
        record = {"turn": self.manager.turn + 1, "kind": decision.action.kind, "phi_before": before.tolist(),
                  "phi_seen": candidates.current[:k].tolist(),
                  "expected_after": candidates.expected[index, :k].tolist(), "predicted": predicted[index].tolist(),
                  "alternatives": alternatives, "accuracy_before": accuracy_now}
        if self.accuracy_what_if:
            test_X, test_y = self.manager._test  # the held-out pool the manager scores (drawn once, read here)
            record["predicted_accuracy"] = predicted_accuracy(state, decision.action, test_X, test_y) - accuracy_now
        self._pending = record

    def on_turn(self, record: dict, scene) -> None:
        if self._pending is None:
            self.quiet_turns += record["action"]["kind"] == "none"
            return
        state, pending = self.manager.state, self._pending
        after = learning_features(state.probabilities(), concept_counts(state))  # same scene: it changes next turn
        pending.update(phi_after=after.tolist(), realised=(after - np.array(pending["phi_before"])).tolist(),
                       answer=record["answer"], realised_accuracy_turn=record["accuracy"] - pending["accuracy_before"])
        self.records.append(pending)
        self._pending = None

    def finish(self, final_accuracy: float) -> list[dict]:
        for record in self.records:
            record["realised_accuracy_end"] = final_accuracy - record["accuracy_before"]
        return self.records


@dataclass(frozen=True)
class CalibrationTask:
    spec: EpisodeSpec
    accuracy_what_if: bool = True
    record: bool = True  # False: the same episode without the recorder (the test that it changes nothing)
    feature_guesses: bool = False  # also probe the FSQ's guessed answers (dialog.experiments.fsq_guesses)
    horizon: bool = False  # ... and read them over the examples the episode can still gather


def play(task: CalibrationTask) -> dict:
    """One episode of ``task.spec`` with the recorder: its records, quiet turns, final accuracy, actions."""
    spec = task.spec
    with one_blas_thread(), tempfile.TemporaryDirectory(prefix="teachbot-whatif-") as scratch:
        pools = load_pools(spec.task, spec.kitchen, spec.dataset + 1, spec.plan, data_seed=spec.data_seed)
        c = spec.condition
        environment = PoolEnvironment(pools.train[spec.dataset], pools.test, pools.task,
                                      -(-c.turns // max(c.change_every, 1)), c.objects_per_scene, c.state_schedule)
        settings = spec.settings()
        rngs = episode_generators(settings.seed)
        timing = embodied_timing(c.seconds)  # as dialog.experiments.episodes builds an episode
        teacher = suite_teacher(dict(spec.teacher), rngs["teacher"], timing.clock, timing.answer_delays)
        strategy = settings.build_strategy()
        recorder = WhatIfRecorder(strategy, task.accuracy_what_if)
        actions: list[dict] = []

        class Actions:
            def on_turn(self, record, scene):
                actions.append(record["action"])

        observers = (recorder, Actions()) if task.record else (Actions(),)
        if task.feature_guesses:
            from dialog.experiments.fsq_guesses import FeatureGuessProbe

            probe = FeatureGuessProbe(pools.task.relevant_features, horizon=task.horizon)
            observers += (probe,)
        with TranscriptWriter(str(Path(scratch) / "episode.jsonl")) as transcript:
            manager = build_episode(settings, environment, teacher, transcript, strategy=strategy, rngs=rngs,
                                    say=lambda _: None, clock=timing.clock, observers=observers)
            recorder.attach(manager)
            if task.feature_guesses:
                probe.attach(manager)
            result = manager.run()
    return {"strategy": spec.strategy, "dataset": spec.dataset, "seed": spec.seed, "accuracy": result.accuracy,
            "records": recorder.finish(result.accuracy) if task.record else [], "quiet_turns": recorder.quiet_turns,
            "actions": actions, "feature_guesses": probe.finish(manager.state) if task.feature_guesses else []}


def calibration_specs(strategies, data_seed: int, datasets: int, seeds, turns: int | None = None,
                      plan: tuple | None = None) -> list[EpisodeSpec]:
    """Every (strategy, data set, seed) in the training allocation (ch7-training's condition) on ``data_seed``."""
    condition = training_condition()
    c = condition.condition if turns is None else replace(condition.condition, turns=turns)
    return [EpisodeSpec(suite="whatif-calibration", task=condition.task, kitchen=condition.kitchen, strategy=s,
                        condition=c, dataset=d, seed=seed, costs=condition.costs, teacher=condition.teacher,
                        transcript="", plan=condition.plan if plan is None else plan, data_seed=data_seed)
            for s in strategies for d in range(datasets) for seed in seeds]


def run_calibration(specs: list[EpisodeSpec], workers: int = 2, accuracy_what_if: bool = True,
                    feature_guesses: bool = False, horizon: bool = False) -> list[dict]:
    """Play every spec with the recorder (and the FSQ-guess probe), on ``workers`` processes; results in spec order."""
    tasks = [CalibrationTask(spec, accuracy_what_if, feature_guesses=feature_guesses, horizon=horizon)
             for spec in specs]
    if workers == 1 or len(tasks) == 1:
        return [play(task) for task in tasks]
    with ProcessPoolExecutor(workers) as pool:
        return list(pool.map(play, tasks))


TARGETS = tuple(LEARNING_FEATURES) + ("accuracy_turn", "accuracy_end")


def pairs(records: list[dict], target: str) -> tuple[np.ndarray, np.ndarray]:
    """(predicted, realised) of one target over records: a learning feature, or held-out accuracy at the turn
    or by the end (both against the one-step predicted accuracy change)."""
    if target in LEARNING_FEATURES:
        j = LEARNING_FEATURES.index(target)
        return (np.array([r["predicted"][j] for r in records]), np.array([r["realised"][j] for r in records]))
    key = {"accuracy_turn": "realised_accuracy_turn", "accuracy_end": "realised_accuracy_end"}[target]
    return (np.array([r["predicted_accuracy"] for r in records]), np.array([r[key] for r in records]))


def calibration_table(records: list[dict]) -> list[dict]:
    """Per kind and target: n, mean predicted, mean realised, Pearson correlation (None when either side is
    constant), mean absolute error."""
    rows = []
    for kind in KINDS:
        mine = [r for r in records if r["kind"] == kind]
        for target in TARGETS:
            if not mine or (target.startswith("accuracy") and "predicted_accuracy" not in mine[0]):
                continue
            p, q = pairs(mine, target)
            correlation = float(np.corrcoef(p, q)[0, 1]) if len(p) > 1 and p.std() > 0 and q.std() > 0 else None
            rows.append({"kind": kind, "target": target, "n": len(p), "predicted": float(p.mean()),
                         "realised": float(q.mean()), "correlation": correlation,
                         "mae": float(np.abs(p - q).mean())})
    return rows
