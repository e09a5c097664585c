"""Expert questioning mode: a person (or the scripted expert) chooses the robot's questions (thesis §7.3.2, §7.4.1).

The one loop stays ``DialogManager``: ``ExpertStrategy`` is an ordinary
strategy whose ``choose`` computes every candidate action and its expected
decision features exactly as the DT strategy does at run time
(``learning.decision.candidates.expected_decision_features`` with the same what-if engine
and window), hands them to a *chooser* (``dialog.expert.terminal.PersonChooser``
or ``dialog.expert.scripted.ScriptedExpertChooser``, the rules of the ``scripted-expert``
strategy), and records the turn as
an IRL ``DecisionTurn`` (Phi of every candidate, the chosen row). A scripted
teacher answers through the manager as in any episode. A chooser ends the
session early by raising ``ExpertQuit``.

``run_expert_episode`` writes two files into the output directory: the IRL
demonstration (``<name>.json``, learning/irl_data format) and the dialog
transcript (``<name>.jsonl``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from dialog.clock import VirtualClock
from dialog.episode import build_episode
from dialog.manager import EpisodeResult, episode_generators
from dialog.settings import EpisodeSettings
from dialog.teachers.scripted import ScriptedTeacher
from dialog.transcripts.jsonl import TranscriptWriter
from learning.actions import Action, Decision
from learning.decision.candidates import CandidateFeatures, expected_decision_features
from learning.decision.habits import EXTENDED_FEATURE_NAMES
from learning.errors import OutputPathError, SettingsError
from learning.irl.demonstrations import DecisionTurn, QuestioningEpisode, save_episodes
from learning.state import LearningState
from learning.strategies.base import Strategy
from learning.whatif import make_engine

# The DT-task-env strategy's defaults (learning.strategies.decision_theoretic): what is recorded is what it computes.
DT_ENGINE = "fast"
DT_WINDOW_FACTOR = 1.0


class ExpertQuit(Exception):  # noqa: N818 - a signal, not an error
    """Raised by a chooser to end the session; the turns so far are kept."""


@dataclass(frozen=True)
class ExpertView:
    """What the expert sees before choosing: the turn, the learner's state and every candidate with E[phi(s')|a]."""

    turn: int  # 1-based
    state: LearningState
    candidates: CandidateFeatures
    rng: np.random.Generator
    scene: object = None  # the bullet_world Scene in front of the robot (what a person looking at it sees)

    def cost(self, action: Action) -> float:
        return self.state.cost(action)


class Chooser(Protocol):
    name: str

    def choose(self, view: ExpertView) -> Action:
        """One of ``view.candidates.actions``; raise ExpertQuit to stop."""


def action_label(action: Action) -> str:
    """Short names used in the demonstration files and the expert's table: LQ(object 4), DQ(fruit), FSQ, no query."""
    if action.kind == "label":
        return f"LQ(object {action.object_index + 1})"
    if action.kind == "demo":
        return f"DQ({action.concept})"
    if action.kind == "feature":
        return "FSQ"
    return "no query"


class ExpertStrategy(Strategy):
    """A strategy that asks a chooser and records every turn's candidates for IRL (thesis eq. 7.1, 7.5)."""

    def __init__(self, chooser: Chooser, engine=DT_ENGINE, window_factor: float = DT_WINDOW_FACTOR):
        self.chooser = chooser
        self.name = f"expert-{chooser.name}"
        self.engine = make_engine(engine)
        self.window_factor = window_factor
        self.turns: list[DecisionTurn] = []
        self.scene = None

    def on_scene(self, scene) -> None:
        """Manager observer hook: the scene the expert is looking at."""
        self.scene = scene

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        # every feature DT-task-env may weigh: the thesis's seven and the expert-habit features (docs/irl.md)
        candidates = expected_decision_features(state, self.engine, self.window_factor, habits=True)
        if len(candidates.actions) == 1:  # only no query is left: nobody needs to be asked
            action = candidates.actions[0]
            explanation = self.nothing_affordable(state).explanation
        else:
            action = self.chooser.choose(ExpertView(state.turn + 1, state, candidates, rng, self.scene))
            if action not in candidates.actions:
                raise ValueError(f"the {self.chooser.name} chose {action_label(action)}, which is not a candidate "
                                 f"this turn; candidates: {', '.join(map(action_label, candidates.actions))}")
            explanation = f"The {self.chooser.name} chose {action_label(action)}."
        self.turns.append(DecisionTurn(candidates.expected, candidates.actions.index(action), candidates.kinds,
                                       tuple(action_label(a) for a in candidates.actions)))
        return Decision(action, explanation)

    def episode(self, name: str, metadata: dict) -> QuestioningEpisode:
        return QuestioningEpisode(EXTENDED_FEATURE_NAMES, tuple(self.turns), name, metadata)


@dataclass(frozen=True)
class ExpertSettings(EpisodeSettings):
    """One expert episode; the defaults are the thesis's training condition (§7.4.1), and a scripted teacher
    with these mislabel and don't-know rates answers."""

    task: str = "prepare-lunch"
    budget: float = 15.0
    change_every: int = 10
    mislabel_rate: float = 0.0
    dont_know_rate: float = 0.0

    def __post_init__(self):
        super().__post_init__()
        for name, value in (("mislabel_rate", self.mislabel_rate), ("dont_know_rate", self.dont_know_rate)):
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and 0 <= value <= 1):
                raise SettingsError(f"{name} must be between 0 and 1, got {value!r}")

    def name(self, expert: str) -> str:
        return f"{expert}-{self.task}-seed{self.seed}"

    def metadata(self) -> dict:
        return {"task": self.task, "kitchen": self.kitchen, "budget": self.budget, "turns": self.turns,
                "change_every": self.change_every, "seed": self.seed, "costs": dict(self.costs),
                "teacher": {"kind": "scripted", "mislabel_rate": self.mislabel_rate,
                            "dont_know_rate": self.dont_know_rate},
                "engine": DT_ENGINE, "window_factor": DT_WINDOW_FACTOR}


@dataclass(frozen=True)
class ExpertOutcome:
    episode: QuestioningEpisode
    result: EpisodeResult
    demonstration: Path
    transcript: Path


def output_paths(out_dir: str | Path, name: str) -> tuple[Path, Path]:
    """(demonstration .json, transcript .jsonl) in ``out_dir``; refuses to overwrite either."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise OutputPathError(f"--out {out_dir} is a file; give a directory for the demonstration and transcript")
    demonstration, transcript = out_dir / f"{name}.json", out_dir / f"{name}.jsonl"
    for path in (demonstration, transcript):
        if path.exists():
            raise OutputPathError(f"{path} already exists; choose another --out directory or --seed")
    return demonstration, transcript


def run_expert_episode(settings: ExpertSettings, chooser: Chooser, out_dir: str | Path, environment=None,
                       say=print, observers: tuple = (), name: str | None = None,
                       metadata: dict | None = None) -> ExpertOutcome:
    """Play one episode with ``chooser`` picking the questions and a scripted teacher answering; save both files.

    ``environment`` defaults to a SimulatedKitchen for the settings (closed afterwards); ``name`` to
    ``settings.name(chooser.name)``; ``metadata`` is added to the demonstration's (e.g. where its scenes came from).
    """
    name = name or settings.name(chooser.name)
    demonstration, transcript_path = output_paths(out_dir, name)
    owned = environment is None
    if owned:
        from dialog.environment import SimulatedKitchen

        environment = SimulatedKitchen(task=settings.task, kitchen=settings.kitchen, seed=settings.seed)
    try:
        rngs = episode_generators(settings.seed)
        clock = VirtualClock()
        teacher = ScriptedTeacher(rngs["teacher"], settings.mislabel_rate, settings.dont_know_rate, clock=clock)
        strategy = ExpertStrategy(chooser)
        session = {"command": "expert", "task": settings.task, "kitchen": settings.kitchen,
                   "teacher": teacher.options(), "expert": chooser.name}
        with TranscriptWriter(transcript_path) as transcript:
            manager = build_episode(settings, environment, teacher, transcript, strategy=strategy, rngs=rngs, say=say,
                                    observers=(strategy, *observers), clock=clock, session=session)
            started = time.perf_counter()
            try:
                result = manager.run()
            except ExpertQuit:
                manager.quit = True
                result = manager.finish(time.perf_counter() - started)
    finally:
        if owned:
            environment.close()
    if not strategy.turns:
        transcript_path.unlink(missing_ok=True)
        raise ExpertQuit("the session ended before the first choice; nothing was saved")
    recorded = {**settings.metadata(), **(metadata or {}), "expert": chooser.name, "completed": len(strategy.turns),
                "quit": result.quit, "accuracy": round(result.accuracy, 6), "budget_spent": result.budget_spent,
                "transcript": transcript_path.name}
    episode = strategy.episode(name, recorded)
    save_episodes(demonstration, [episode])
    return ExpertOutcome(episode, result, demonstration, transcript_path)
