"""The dialog manager: the timed, budgeted teaching loop (thesis §6.3.2, §7.3.3).

Each turn: observe (a new scene every ``change_every`` turns), let the strategy
choose one action, realise it (point, ask, listen), update the learner, and
append the turn to the transcript before the next one begins.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from dialog.environment import Environment
from dialog.teachers import Answer, Teacher
from dialog.transcript import TranscriptWriter
from learning.actions import DEFAULT_COSTS, Action, NoQuery
from learning.evaluation import accuracy
from learning.state import LearningState
from learning.strategies import Strategy


@dataclass
class EpisodeConfig:
    """One episode's allocation: T turns, budget B, a scene change every r turns."""

    turns: int = 30
    budget: float = 40.0
    change_every: int = 5
    seed: int = 0
    costs: dict = field(default_factory=lambda: dict(DEFAULT_COSTS))

    def __post_init__(self):
        if self.turns < 1:
            raise ValueError(f"turns must be at least 1, got {self.turns}")
        if self.budget < 0:
            raise ValueError(f"budget must be zero or more, got {self.budget}")
        if self.change_every < 1:
            raise ValueError(f"change-every must be at least 1 turn, got {self.change_every}")


@dataclass
class EpisodeResult:
    seed: int
    strategy: str
    turns: int
    budget_spent: float
    queries: dict
    accuracy: float
    transcript: str
    seconds: float


def episode_generators(seed: int) -> dict[str, np.random.Generator]:
    """Independent random streams from one seed, one per consumer."""
    names = ("scenes", "test", "strategy", "teacher")
    children = np.random.SeedSequence(seed).spawn(len(names))
    return {name: np.random.default_rng(child) for name, child in zip(names, children)}


def question_text(action: Action, object_number: int | None = None) -> str:
    if action.kind == "label":
        return f"What is this (object {object_number})?"
    if action.kind == "demo":
        return f"Can you show me a {action.concept}?"
    if action.kind == "feature":
        return "Which features tell these things apart?"
    return ""


class DialogManager:
    """Runs one episode of the loop with any environment, teacher and strategy."""

    def __init__(self, environment: Environment, teacher: Teacher, strategy: Strategy, config: EpisodeConfig,
                 transcript: TranscriptWriter, rngs: dict[str, np.random.Generator], say=print,
                 observers: tuple = ()):
        self.env, self.teacher, self.strategy = environment, teacher, strategy
        self.config, self.transcript, self.rngs, self.say = config, transcript, rngs, say
        self.observers = tuple(observers)
        self.state = LearningState(environment.concepts, environment.feature_names, config.budget, config.turns,
                                   costs=config.costs, change_every=config.change_every)

    def run(self) -> EpisodeResult:
        started = time.perf_counter()
        test_X, test_y = self.env.test_set(getattr(self.env, "test_scenes", 4), self.rngs["test"])
        scene = None
        for turn in range(self.config.turns):
            if turn % self.config.change_every == 0:
                scene = self.env.next_scene(self.rngs["scenes"])
                self.state.observe_scene(scene.scene_id, scene.X)
                self._notify("on_scene", scene)
                self.say(f"-- turn {turn + 1}: the robot looks at a new scene of {scene.n_objects} objects")
            record = self._turn(turn, scene)
            record["accuracy"] = round(accuracy(self.state.predict(test_X), test_y), 6)
            self.transcript.write(record)
            self._notify("on_turn", record, scene)
        final = accuracy(self.state.predict(test_X), test_y)
        kinds = Counter(self.state.history)
        return EpisodeResult(
            seed=self.config.seed, strategy=self.strategy.name, turns=self.config.turns,
            budget_spent=self.state.spent,
            queries={"label": kinds["label"], "demo": kinds["demo"], "feature": kinds["feature"],
                     "none": kinds["none"]},
            accuracy=final, transcript=str(self.transcript.path), seconds=time.perf_counter() - started,
        )

    def _turn(self, turn: int, scene) -> dict:
        decision = self.strategy.choose(self.state, self.rngs["strategy"])
        action = decision.action if self.state.can_afford(decision.action) else NoQuery()
        record = {"turn": turn + 1, "scene_id": scene.scene_id, "action": _action_record(action),
                  "explanation": decision.explanation}
        if action.kind == "none":
            answer = Answer("")
            self.say(f"Turn {turn + 1:>3} · Robot stays quiet. ({decision.explanation})")
        else:
            number = action.object_index + 1 if action.kind == "label" else None
            question = question_text(action, number)
            if action.kind == "label":
                record["gesture"] = self.env.point_at(scene, action.object_index)
                lead = f"Robot (pointing at object {number})"
            else:
                lead = "Robot"
            answer = self.teacher.answer(action, question, scene)
            self._apply(action, answer, scene)
            record["question"] = question
            self.say(f"Turn {turn + 1:>3} · {lead}: {question}   Teacher: {answer.raw}")
        self.state.record_turn(action)
        record.update({
            "answer": {"raw": answer.raw, "parsed": _jsonable(answer.value)},
            "cost": self.state.cost(action), "budget_left": self.state.remaining_budget,
            "model": {"examples": self.state.counts_per_concept()},
        })
        return record

    def _notify(self, event: str, *payload) -> None:
        """Tell observers (a viewer, a progress display) what happened; they may not change the episode."""
        for observer in self.observers:
            handler = getattr(observer, event, None)
            if handler is not None:
                handler(*payload)

    def _apply(self, action: Action, answer: Answer, scene) -> None:
        if answer.value is None:
            return
        if action.kind == "label":
            self.state.add_example(scene.X[action.object_index], answer.value, "label")
        elif action.kind == "demo":
            self.state.add_example(scene.X[answer.value], action.concept, "demo")
        elif action.kind == "feature":
            self.state.set_feature_subset(answer.value)


def _action_record(action: Action) -> dict:
    record = {"kind": action.kind}
    if action.kind == "label":
        record["object"] = action.object_index + 1
    elif action.kind == "demo":
        record["concept"] = action.concept
    return record


def _jsonable(value):
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_jsonable(v) for v in value]
    return value
