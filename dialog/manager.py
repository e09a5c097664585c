"""The dialog manager: the timed, budgeted teaching loop (thesis §6.3.2, §7.3.1, §7.3.3).

Each turn: observe (a new scene every ``change_every`` turns, or, in real-time
mode, whenever the world's own clock says so), let the strategy choose one
action, realise it (point, ask, listen, learn), and append the turn to the
transcript before the next one begins. At most one query per turn; once the
budget is spent only "no query" remains.

``play_turn(action)`` realises one given action, so that a person (expert
mode) can choose the questions instead of a strategy; ``run(replay=records)``
first replays recorded turns into a fresh state (``--resume``).
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass

import numpy as np

from dialog.clock import VirtualClock
from dialog.embodied import load_embodied_costs
from dialog.environment import DEFAULT_TEST_SCENES, Environment, HasTestScenes, SupportsFetch
from dialog.language.parsing import AnswerParser
from dialog.language.questions import Prompt, Questioner, acknowledgement, article, question_text
from dialog.settings import EpisodeConfig
from dialog.teachers.conversation import Outcome, converse
from dialog.teachers.protocol import checked_teacher
from dialog.transcripts import records as checks
from dialog.transcripts.jsonl import TranscriptWriter
from dialog.transcripts.records import action_record, answer_record
from dialog.transcripts.replay import replay_turn
from learning.actions import Action
from learning.answers import DemoRow
from learning.evaluation import accuracy
from learning.state import LearningState
from learning.strategies import Strategy
from learning.strategies.check import refuse_invalid_decision
from learning.strategies.plugins import is_plugin
from learning.turn import admissible, budget_spent, scene_epoch

__all__ = ["DialogManager", "EpisodeConfig", "EpisodeResult", "episode_generators", "question_text"]

STREAMS = ("scenes", "test", "strategy", "teacher", "pantry")
OBSERVER_EVENTS = ("on_scene", "on_decision", "on_question", "on_answer", "on_turn")


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
    completed: int = 0
    quit: bool = False
    #: embodied costs: the accuracy after the last turn that ended within the allocation's seconds and how many
    #: turns that is (the turn in progress when the seconds ran out does not count, docs/experiments.md)
    allocation_accuracy: float | None = None
    allocation_turns: int = 0
    #: why the episode ended: "budget" (spent, the chapter-6 ending), "bound" (the turns ran out while ending
    #: on the budget), "turns" (the allocation's turns), "seconds" (embodied costs) or "quit"
    ended: str = "turns"


def episode_generators(seed: int) -> dict[str, np.random.Generator]:
    """Independent random streams from one seed, one per consumer."""
    children = np.random.SeedSequence(seed).spawn(len(STREAMS))
    return {name: np.random.default_rng(child) for name, child in zip(STREAMS, children)}


class DialogManager:
    """Runs one episode of the loop with any environment, teacher and strategy.

    Observers may define any of ``on_scene(scene)``, ``on_question(action, text, scene)``,
    ``on_answer(action, outcome, scene)`` and ``on_turn(record, scene)``. The teacher and the environment's
    optional abilities (``dialog.environment``: SupportsFetch, HasTestScenes) are checked once, here.
    """

    def __init__(self, environment: Environment, teacher, strategy: Strategy, config: EpisodeConfig,
                 transcript: TranscriptWriter, rngs: dict[str, np.random.Generator], say=print,
                 observers: tuple = (), clock=None, parser: AnswerParser | None = None, session: dict | None = None):
        self.env, self.teacher, self.strategy = environment, checked_teacher(teacher), strategy
        self.config, self.transcript, self.say = config, transcript, say
        self.rngs = dict(rngs)
        if "pantry" not in self.rngs:
            self.rngs["pantry"] = episode_generators(config.seed)["pantry"]
        self.observers = tuple(observers)
        self._handlers = {event: tuple(getattr(o, event) for o in self.observers if callable(getattr(o, event, None)))
                          for event in OBSERVER_EVENTS}
        self.can_fetch = isinstance(environment, SupportsFetch)
        self.test_scenes = environment.test_scenes if isinstance(environment, HasTestScenes) else DEFAULT_TEST_SCENES
        self.clock = clock or VirtualClock()
        self.parser = parser or AnswerParser(environment.concepts)
        self.session = dict(session or {})
        self.state = LearningState(environment.concepts, environment.feature_names, config.budget, config.turns,
                                   costs=config.costs, change_every=config.change_every,
                                   feature_selection=getattr(strategy, "feature_selection", None))
        self.scene = None
        self.turn = 0  # turns finished
        self.quit = False
        self.replay_mismatches = 0
        self._epoch = -1
        self._test = None
        self._test_accuracy: tuple[int, float] | None = None  # (model version, held-out accuracy)
        self._undo_stack: list[tuple] = []
        self.questioner = Questioner(environment, self.state, config.pictures)
        self._fetched_words = ""  # the last object fetched from the pantry, in words (told to the teacher)
        self.embodied = load_embodied_costs() if config.seconds is not None else None  # dialog/embodied.py
        self._pointing: tuple | None = None  # ((scene id, last pointed), each object's expected pointing seconds)
        self._last_pointed: int | None = None  # the scene object the arm points at now (None: at rest)
        self._within_allocation: tuple[float | None, int] = (None, 0)  # (accuracy, turns) ended within the seconds

    # -- episode ------------------------------------------------------------------
    def header(self) -> dict:
        config = self.config
        return {"seed": config.seed, "turns": config.turns, "budget": config.budget,
                "change_every": config.change_every, "realtime": config.realtime, "costs": dict(config.costs),
                "fetch_from_pantry": config.fetch_from_pantry, "strategy": self.strategy.name,
                "concepts": list(self.env.concepts), "features": len(self.env.feature_names),
                **getattr(self.strategy, "header_fields", dict)(), **self.session,
                **({"until_budget_spent": True} if config.until_budget_spent else {}),
                **({} if self.embodied is None else {"seconds": config.seconds,
                                                     "embodied_costs": self.embodied.record()})}

    def begin(self) -> None:
        """Draw the held-out test set and write the session header (once)."""
        if self._test is None:
            test_X, test_y = self.env.test_set(self.test_scenes, self.rngs["test"])
            test_X = np.array(test_X, dtype=float)  # our own read-only copy: the state scales it once per scaler
            test_X.setflags(write=False)
            self._test = (test_X, test_y)
        if not self.transcript.has_content:
            self.transcript.write_header(self.header())

    def run(self, replay: list[dict] = ()) -> EpisodeResult:
        """Play the episode; recorded turns in ``replay`` are re-applied first, without asking anyone."""
        started = time.perf_counter()
        self.begin()
        replay = list(replay)
        while self.turn < self.config.turns and not self.quit:
            if self.config.until_budget_spent and budget_spent(self.state):
                break
            if self.turn < len(replay):
                self.replay_turn(replay[self.turn])
            elif self.out_of_time():
                break
            else:
                self.play_turn()
        return self.finish(time.perf_counter() - started)

    def finish(self, seconds: float = 0.0) -> EpisodeResult:
        kinds = Counter(self.state.history)
        return EpisodeResult(
            seed=self.config.seed, strategy=self.strategy.name, turns=self.config.turns,
            budget_spent=self.state.spent,
            queries={"label": kinds["label"], "demo": kinds["demo"], "feature": kinds["feature"],
                     "none": kinds["none"]},
            accuracy=self.test_accuracy(), transcript=str(self.transcript.path),
            seconds=seconds, completed=self.turn, quit=self.quit,
            allocation_accuracy=self._within_allocation[0], allocation_turns=self._within_allocation[1],
            ended=self.ending(),
        )

    def ending(self) -> str:
        """Why the episode ended, or would end now (``EpisodeResult.ended``)."""
        if self.quit:
            return "quit"
        if self.config.until_budget_spent:
            return "budget" if budget_spent(self.state) else "bound"
        return "seconds" if self.out_of_time() else "turns"

    # -- the clock and the world ---------------------------------------------------
    def out_of_time(self) -> bool:
        """With embodied costs: the seconds allocation is used up (the turns cap is checked by the loop)."""
        return self.embodied is not None and self.clock.now() >= self.config.seconds

    def begin_turn(self) -> float:
        """Start the next turn (the scene changes when it is due) and return its start time; then ``realise``
        one action. ``play_turn`` does both; a caller that chooses the action itself after seeing the turn's
        scene (the Gymnasium environment, dialog/rl/gym_env.py) calls them one after the other."""
        return self._start_turn()

    def _start_turn(self, recorded_scene: int | None = None) -> float:
        """Wait for the turn's slot (real time), and change the scene when it is due."""
        config = self.config
        if config.realtime:
            self.clock.sleep_until(self.turn * config.realtime)
            start = self.clock.now()
            epoch = int(start // (config.change_every * config.realtime))
        elif self.embodied is not None:  # embodied costs: the world changes with time, not with the turn count
            start = self.clock.now()
            epoch = int(start // self.embodied.scene_seconds(config.change_every))
        else:
            start = self.clock.now()
            epoch = scene_epoch(self.turn, config.change_every)
        due = self.scene is None or epoch > self._epoch
        if recorded_scene is not None:
            due = self.scene is None or recorded_scene != self.scene.scene_id
        if due:
            self.scene = self.env.next_scene(self.rngs["scenes"])
            self._epoch = max(epoch, self._epoch + 1)
            self.state.observe_scene(self.scene.scene_id, self.scene.X)
            self._last_pointed = None  # the arm rests before the world is observed again
            self._notify("on_scene", self.scene)
            self.say(f"-- turn {self.turn + 1}: the robot looks at a new scene of {self.scene.n_objects} objects")
        if self.embodied is not None:
            self.state.set_seconds_clock(self.embodied.clock(self.config.seconds, start, self.pointing_seconds(),
                                                             self.config.fetch_from_pantry and self.can_fetch))
        return start

    def pointing_seconds(self) -> np.ndarray:
        """Each scene object's expected pointing seconds (embodied costs), from its measured distance and bearing,
        from rest or from the object the arm points at now."""
        key = (self.scene.scene_id, self._last_pointed)
        if self._pointing is None or self._pointing[0] != key:
            self._pointing = (key, self.embodied.pointing_seconds(self.scene.X, self.scene.feature_names,
                                                                  self._last_pointed))
        return self._pointing[1]

    def note_pointed(self, index: int | None) -> None:
        """The arm now points at scene object ``index`` (None: it rested, e.g. after a fetch)."""
        self._last_pointed = index

    # -- one turn -----------------------------------------------------------------------
    def play_turn(self, action: Action | None = None, explanation: str = "") -> dict | None:
        """Choose (or take the given) action and realise it; None when the teacher quit."""
        start = self._start_turn()
        if action is None:
            decision = self.strategy.choose(self.state, self.rngs["strategy"])
            action, explanation = decision.action, decision.explanation
            self._notify("on_decision", decision)
        chosen = action
        action, reason = admissible(self.state, chosen)  # learning.turn: the library's rules
        if action != chosen and is_plugin(self.strategy):  # the user's code is held to the contract, not mended
            raise refuse_invalid_decision(self.strategy.name, chosen, reason, self.turn + 1)
        return self.realise(action, reason or explanation, start, chosen)

    def realise(self, action: Action, explanation: str, start: float, chosen: Action | None = None) -> dict | None:
        """Point, ask, listen and learn for one action; append the turn's record. None if the teacher quit."""
        scene, number = self.scene, self.turn + 1
        record = {"turn": number, "time": round(start, 3), "scene_id": scene.scene_id,
                  "scene_check": checks.scene_check(scene), "action": action_record(action), "explanation": explanation}
        if chosen is not None and chosen != action:
            record["strategy_action"] = action_record(chosen)
        message = ""
        if action.kind == "none":
            outcome = Outcome("none")
            if self.embodied is not None:
                self.clock.advance(self.embodied.quiet)
            self.say(f"{self._turn_label(number, start)} · Robot stays quiet. ({explanation})")
        else:
            if action.kind == "label":
                record["gesture"] = self.env.point_at(scene, action.object_index)
                if self.embodied is not None and "sim_seconds" not in record["gesture"]:  # no arm: the model's time
                    modelled = round(float(self.pointing_seconds()[action.object_index]), 3)
                    record["gesture"] = {**record["gesture"], "model_seconds": modelled}
                    self.clock.advance(modelled)
                self.clock.advance(record["gesture"].get("sim_seconds", 0.0))
                self.note_pointed(action.object_index)
            if self.embodied is not None:  # saying the question
                self.clock.advance(self.embodied.speaking[action.kind])
            prompt = self.prompt_for(action, explanation, number, start)
            record["question"] = prompt.text
            if prompt.picture:
                record["picture"] = prompt.picture
            self._notify("on_question", action, prompt.text, scene)
            outcome, undone = self._ask(prompt)
            if outcome.kind == "quit":
                self.quit = True
                self.say(f"{self._turn_label(number, start)} · the teacher ended the session "
                         f"({outcome.note or 'quit'}).")
                return None
            for _ in undone:
                self._undo()
            if undone:
                record["undid"] = undone
            record.update(self._apply(action, outcome, scene))
            message = acknowledgement(prompt, outcome.kind, outcome.value, self.env.feature_names)
            if "fetched" in record:
                message = f"There's none here, so I fetched one from the pantry: {self._fetched_words}."
            elif "fetch_failed" in record:
                message = ("There's none here, and I couldn't fetch one from the pantry: "
                           f"{record['fetch_failed']['reason']}. I'll go on without one.")
            self._notify("on_answer", action, outcome, scene)
            lead = f"Robot (pointing at object {action.object_index + 1})" if action.kind == "label" else "Robot"
            self.say(f"{self._turn_label(number, start)} · {lead}: {prompt.text}   Teacher: {outcome.raw}")
        record = self._close_turn(record, action, outcome)
        if action.kind != "none" and message:  # acknowledged only once the turn is on disk
            self.teacher_tell(message)
        return record

    def _close_turn(self, record: dict, action: Action, outcome: Outcome) -> dict:
        if self.state.turn == self.turn:  # nothing applied this turn (no question was asked): record it as such
            self.state.apply(action, None)
        record.update({
            "answer": answer_record(outcome, action, self.state.feature_names),
            "cost": self.state.cost(action), "budget_left": self.state.remaining_budget,
            "model": self.model_summary(),
            "ended": round(self.clock.now(), 3),
            "accuracy": round(self.test_accuracy(), 6),
        })
        if self.embodied is not None:  # how long the turn took
            record["seconds"] = round(record["ended"] - record["time"], 3)
            if record["ended"] <= self.config.seconds:
                self._within_allocation = (record["accuracy"], record["turn"])
        self.transcript.write(record)
        self.turn += 1
        self._notify("on_turn", record, self.scene)
        return record

    def test_accuracy(self) -> float:
        """Accuracy on the held-out test set, computed once per model version: the models and the scaler change
        only in a refit, which bumps the version, so a turn that taught nothing reuses the last value exactly."""
        version = self.state.version
        if self._test_accuracy is None or self._test_accuracy[0] != version:
            test_X, test_y = self._test
            self._test_accuracy = (version, accuracy(self.state.predict(test_X), test_y))
        return self._test_accuracy[1]

    def _ask(self, prompt: Prompt) -> tuple[Outcome, list[int]]:
        """Converse until the question ends; "undo" takes back earlier answers (applied once it ends)."""
        lines, channels, undone = [], [], []
        while True:
            outcome = converse(self.teacher, prompt, self.parser, self.clock)
            lines += outcome.lines
            channels += outcome.channels
            if outcome.kind != "undo":
                break
            if len(undone) >= len(self._undo_stack):
                self.teacher_tell("There is nothing left to take back.")
                continue
            turn, what = self._undo_stack[-1 - len(undone)][:2]
            undone.append(turn)
            refunded = sum(entry[2].cost for entry in self._undo_stack[len(self._undo_stack) - len(undone):])
            if hasattr(self.teacher, "budget_changed"):  # the page's budget line follows the undo at once
                self.teacher.budget_changed(prompt.budget_left + refunded)
            self.teacher_tell(f"Taken back: {what} (turn {turn}); that question is not asked again unless I choose "
                              f"it again. Now: {prompt.text}")
        outcome.lines, outcome.channels = lines, channels
        return outcome, undone

    def _turn_label(self, number: int, start: float) -> str:
        """``Turn  12`` and, with embodied costs, the clock when the turn began: ``Turn  12 at 143.2 s``."""
        return f"Turn {number:>3}" + ("" if self.embodied is None else f" at {start:.1f} s")

    def teacher_tell(self, text: str) -> None:
        self.teacher.tell(text)

    def prompt_for(self, action: Action, explanation: str, number: int, start: float, pictures: bool = True) -> Prompt:
        """The question for ``action`` with its details (table, picture, feature tree)."""
        deadline = start + self.config.realtime if self.config.realtime else None
        return self.questioner.prompt(self.scene, action, explanation, number, deadline, pictures)

    # -- answers -------------------------------------------------------------------------
    def _apply(self, action: Action, outcome: Outcome, scene, replaying: bool = False) -> dict:
        """Learn from the outcome and record the turn (``LearningState.apply``); returns extra transcript
        fields (a pantry fetch)."""
        if outcome.kind == "absent" and action.kind == "demo" and self._may_fetch(action.concept):
            extra, change = self._fetch(action, scene)
        else:
            extra, change = {}, self.state.apply(action, outcome.value if outcome.kind == "answer" else None)
        if change.kind == "example" and change.object is None:
            self._undo_stack.append((self.turn + 1, f"the {change.concept} from the pantry", change))
        elif change.kind == "example":
            self._undo_stack.append((self.turn + 1, f"number {change.object + 1} is {article(change.concept)}", change))
        elif change.kind == "features":
            self._undo_stack.append((self.turn + 1, f"the choice of {len(change.features)} features", change))
        return extra

    def _fetch(self, action: Action, scene) -> tuple[dict, object]:
        """Fetch an example from the pantry and apply it as the demonstration (or, failing that, apply "none
        here"); a fetch that fails is told in the dialog, never raised. Returns the extra fields and the change."""
        fetched = self.env.fetch(scene, action.concept, self.rngs["pantry"]) or {}
        self.clock.advance(fetched.get("sim_seconds", 0.0))
        self.note_pointed(None)  # the arm rests after reaching into the pantry
        reason = fetched.get("reason", "the pantry had none")
        if fetched.get("x") is not None:
            try:
                change = self.state.apply(action, DemoRow(fetched["x"]))
            except ValueError as error:  # the learner refuses the observation; its state is unchanged
                reason = f"my measurements of it were unusable ({error})"
            else:
                kept = {key: fetched[key] for key in ("kind", "position", "replaced") if key in fetched}
                # told in words, as any object (the kind's name is the catalogue's, for the transcript)
                self._fetched_words = self.questioner.describe_fetched(fetched["x"], fetched.get("position"))
                return {"fetched": kept}, change
        return {"fetch_failed": {"kind": fetched.get("kind"), "reason": reason}}, self.state.apply(action, None)

    def _may_fetch(self, concept: str) -> bool:
        return bool(self.config.fetch_from_pantry and self.can_fetch and self.env.can_fetch(concept))

    def _undo(self) -> int:
        """Take back the latest learned answer; returns its turn."""
        turn, _, change = self._undo_stack.pop()
        self.state.undo(change)
        return turn

    def model_summary(self) -> dict:
        subsets = [s for s in self.state.fitted_feature_subsets.values() if s is not None]
        in_use = len(subsets[0]) if subsets else len(self.state.feature_names)
        return {"examples": self.state.counts_per_concept(), "features_in_use": in_use}

    # -- resume ---------------------------------------------------------------------------
    def replay_turn(self, record: dict) -> None:
        """Re-apply one recorded turn and check it against the rebuilt episode (:mod:`dialog.transcripts.replay`)."""
        replay_turn(self, record)

    def _notify(self, event: str, *payload) -> None:
        """Tell observers (a viewer, a progress display) what happened; they may not change the episode."""
        for handler in self._handlers[event]:
            handler(*payload)
