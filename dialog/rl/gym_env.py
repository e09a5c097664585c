"""``teachbot/Questioning-v0``: questioning a teacher under a budget as a Gymnasium environment (beyond the thesis).

Importing this module registers the id (``pip install -e '.[rl]'`` installs
gymnasium)::

    import gymnasium as gym
    import dialog.rl.gym_env  # registers teachbot/Questioning-v0
    env = gym.make("teachbot/Questioning-v0", budget=25, turns=40)

Every step is one turn of the real dialog loop that ``teachbot regress`` runs
(dialog/manager.py with a scripted teacher on the cached kitchen data sets,
dialog/experiments/pools.py): the agent's action is realised, the teacher
answers, the learner's models are refit and scored on the held-out test pool.

* Actions: ``Discrete(n)`` over the fixed slots of learning/rl/observation.py
  (no query, the feature query, a demonstration per concept, a label query per
  scene object, ``objects_per_scene`` of them: the task's own scene size unless given, e.g. 55 for
  pack-lunchbox as in the thesis's experiments). ``info["action_mask"]`` and
  ``action_masks()`` say which slots are candidates this turn (affordable, and
  present in the scene); a masked slot is played as no query and flagged
  ``info["invalid_action"]``.
* Observation: phi(s), each slot's E[phi(s') | a] from the fast what-if engine
  (``whatif=False`` leaves these out) and the mask, all in [0, 1].
* Reward: the held-out accuracy gained this turn, minus ``price`` per unit of
  budget spent (default 0). The episode ends (terminated) at the time allocation.

The defaults are the thesis's chapter-7 training condition, read from
dialog/suites/ch7-training.toml (prepare-lunch, budget 15, 30 turns, a new
scene every 10 turns, costs DQ 2, FSQ 2, LQ 1, data seed 100), so a policy
trained on them has seen none of the data the chapter-7 suite reports on.
``reset(seed=s)`` plays data set ``s mod datasets`` with episode seed ``s``
(``options={"dataset": k}`` plays data set k instead; any other option is
refused): the same seed and actions give the same episode. Every argument is
checked when given (docs/rl.md): an action outside ``action_space`` (``1.7``,
``"0"``, ``True``) raises :class:`InvalidActionError`, an AssertionError as in
Gymnasium's own environments, and a one-line SettingsError.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from os import PathLike

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bullet_world.catalogue import load_task
from dialog.episode import build_episode
from dialog.experiments.episodes import suite_teacher
from dialog.experiments.irl_rollouts import training_condition
from dialog.experiments.pools import PoolEnvironment, load_pools
from dialog.experiments.suite import teacher_options
from dialog.manager import DialogManager, episode_generators
from dialog.rl.allocations import Allocation, ranges_from
from dialog.settings import EpisodeSettings, check_costs
from dialog.transcripts.jsonl import MemoryTranscript, TranscriptWriter
from learning.actions import NoQuery
from learning.decision.features import FEATURE_NAMES
from learning.errors import SettingsError
from learning.limits import check_limit
from learning.rl.observation import Observation, ObservationLayout
from learning.state import LearningState
from learning.strategies.base import Strategy
from learning.whatif import make_engine

ENV_ID = "teachbot/Questioning-v0"
SEED_LIMIT = 2**31  # episode seeds drawn when reset() gets none
RESET_OPTIONS = ("dataset",)  # reset(options=...): the keys accepted


class InvalidActionError(SettingsError, AssertionError):
    """An action outside the action space. Gymnasium's own environments assert
    ``action_space.contains(action)``, so this is an AssertionError too (and a one-line TeachbotError)."""


class AgentChooses(Strategy):
    """The manager's strategy slot when the Gymnasium agent chooses every action through ``step``."""

    name = "gym-agent"

    def choose(self, state: LearningState, rng: np.random.Generator):
        raise RuntimeError("in the Gymnasium environment the agent chooses each action through env.step(action)")


@dataclass(frozen=True)
class QuestioningSettings:
    """Where the episodes are played; None fields come from the ch7-training suite."""

    task: str | None = None
    kitchen: str | None = None
    budget: float | None = None
    turns: int | None = None
    change_every: int | None = None
    costs: dict | None = None
    teacher: dict | None = None  # kind ("scripted" | "oracle"), mislabel_rate, dont_know_rate, feature_quality
    data_seed: int | None = None
    datasets: int | None = None
    objects_per_scene: int | None = None  # None: the task's interactive size (pack-lunchbox's experiments: 55)

    def resolved(self) -> QuestioningSettings:
        """Every field filled in: the given ones, the rest from the training condition."""
        base = training_condition()
        filled = QuestioningSettings(base.task, base.kitchen, base.condition.budget, base.condition.turns,
                                     base.condition.change_every, dict(base.costs), dict(base.teacher),
                                     base.data_seed, base.datasets, None)
        given = {name: value for name, value in self.__dict__.items() if value is not None}
        settings = replace(filled, **given)
        check_costs(settings.costs)
        if not isinstance(settings.teacher, dict):
            raise SettingsError(f"teacher must be a dict of teacher options, got {settings.teacher!r}")
        teacher_options(settings.teacher, "teacher")
        for name in ("datasets", "data_seed"):
            value, low = getattr(settings, name), 1 if name == "datasets" else 0
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
                raise SettingsError(f"{name} must be a whole number of {low} or more, got {value!r}")
        check_limit("datasets", settings.datasets)
        size = settings.objects_per_scene
        if size is not None:
            largest = load_task(settings.task).max_objects_per_scene
            if isinstance(size, bool) or not isinstance(size, int | np.integer) or not 1 <= size <= largest:
                raise SettingsError(f"objects_per_scene must be None or a whole number from 1 to {largest} (the "
                                    f"largest scene of task '{settings.task}'), got {size!r}")
        EpisodeSettings(task=settings.task, kitchen=settings.kitchen, turns=settings.turns, budget=settings.budget,
                        change_every=settings.change_every, costs=dict(settings.costs))  # validates the allocation
        return settings


class QuestioningEnv(gym.Env):
    """One teaching episode per reset; one turn per step (see the module docstring)."""

    metadata = {"render_modes": ["ansi"], "render_fps": 1}

    def __init__(self, task: str | None = None, kitchen: str | None = None, budget: float | None = None,
                 turns: int | None = None, change_every: int | None = None, costs: dict | None = None,
                 teacher: dict | None = None, data_seed: int | None = None, datasets: int | None = None,
                 whatif: bool = True, price: float = 0.0, transcript: str | None = None,
                 render_mode: str | None = None, allocations=None, objects_per_scene: int | None = None):
        self.settings = QuestioningSettings(task, kitchen, budget, turns, change_every, costs, teacher, data_seed,
                                            datasets, objects_per_scene).resolved()
        self.allocations = None if allocations is None else ranges_from(allocations)
        given = [name for name, value in (("budget", budget), ("turns", turns), ("change_every", change_every))
                 if value is not None]
        if self.allocations is not None and given:
            raise SettingsError(f"give either allocations (each episode draws its own) or {', '.join(given)} "
                                "(one allocation for every episode), not both")
        if not isinstance(whatif, bool | np.bool_):
            raise SettingsError(f"whatif must be True or False (each slot's expected features in the observation), "
                                f"got {whatif!r}")
        if transcript is not None and not isinstance(transcript, str | PathLike):
            raise SettingsError(f"transcript must be None or a path, got {transcript!r}")
        if not isinstance(price, int | float) or isinstance(price, bool) or not np.isfinite(price) or price < 0:
            raise SettingsError(f"price must be a number of 0 or more (reward lost per unit of budget), got {price!r}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise SettingsError(f"render_mode must be None or one of {self.metadata['render_modes']}, "
                                f"got {render_mode!r}")
        s = self.settings
        plan = () if s.objects_per_scene is None else (("objects_per_scene", int(s.objects_per_scene)),)
        self.pools = load_pools(s.task, s.kitchen, s.datasets, plan_options=plan, data_seed=s.data_seed)
        self.objects_per_scene = (self.pools.task.objects_per_scene if s.objects_per_scene is None
                                  else int(s.objects_per_scene))
        self.layout = ObservationLayout(tuple(self.pools.task.concepts), self.objects_per_scene,
                                        bool(whatif), allocation=self.allocations is not None)
        self.price, self.transcript_path, self.render_mode = float(price), transcript, render_mode
        self.engine = make_engine("fast")
        self.action_space = spaces.Discrete(self.layout.n_actions)
        self.observation_space = spaces.Box(0.0, 1.0, (self.layout.size,), dtype=np.float32)
        self.manager: DialogManager | None = None
        self._observation: Observation | None = None
        self._turn_start = 0.0
        self._accuracy = 0.0
        self._last: dict = {}
        self._ended = False
        self.episode_seed: int | None = None
        self.allocation: Allocation | None = None

    # -- Gymnasium ------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0):
            raise SettingsError(f"seed must be None or a whole number of 0 or more, got {seed!r}")
        dataset = self._dataset_option(options)  # checked before anything changes
        super().reset(seed=seed)
        self.close()
        if seed is None:
            seed = int(self.np_random.integers(SEED_LIMIT))
        s = self.settings
        self.episode_seed = int(seed)
        self.allocation = (Allocation(float(s.budget), s.turns, s.change_every) if self.allocations is None
                           else self.allocations.draw(self.episode_seed))
        a = self.allocation
        scenes = -(-a.turns // a.change_every)
        dataset = self.episode_seed % s.datasets if dataset is None else dataset
        world = PoolEnvironment(self.pools.train[dataset], self.pools.test, self.pools.task, scenes,
                                self.objects_per_scene)
        rngs = episode_generators(self.episode_seed)
        settings = EpisodeSettings(task=s.task, kitchen=s.kitchen, strategy=AgentChooses.name, seed=self.episode_seed,
                                   turns=a.turns, budget=s.budget if self.allocations is None else a.budget,
                                   change_every=a.change_every, costs=dict(s.costs))
        transcript = MemoryTranscript() if self.transcript_path is None else TranscriptWriter(self.transcript_path)
        self.manager = build_episode(settings, world, suite_teacher(dict(s.teacher), rngs["teacher"]), transcript,
                                     strategy=AgentChooses(), rngs=rngs, say=lambda _: None,
                                     session={"environment": ENV_ID, "dataset": dataset, "data_seed": s.data_seed})
        self.manager.begin()
        self._accuracy = self.manager.finish().accuracy
        self._last, self._ended = {}, False
        self._begin_turn()
        return self._observation_vector(), self._info(invalid=False)

    def step(self, action):
        manager, observation = self._running()
        if self._ended:
            raise SettingsError("the episode ended at its time allocation; call reset() to start another")
        if isinstance(action, bool | np.bool_) or not self.action_space.contains(action):
            raise InvalidActionError(f"action {action!r} ({type(action).__name__}) is not a slot "
                                     f"0..{self.layout.n_actions - 1} of the action space {self.action_space} (an int "
                                     "or a numpy integer, as Discrete.contains accepts; not a bool, float or string)")
        slot = int(action)
        chosen = observation.actions[slot]
        invalid = chosen is None
        record = manager.realise(NoQuery() if chosen is None else chosen,
                                 f"the agent's choice (slot {slot}{', masked: played as no query' if invalid else ''})",
                                 self._turn_start)
        assert record is not None, "a scripted teacher never quits"
        reward = record["accuracy"] - self._accuracy - self.price * record["cost"]
        self._accuracy, self._last = record["accuracy"], record
        terminated = manager.turn >= manager.config.turns
        if terminated:
            self._ended = True
        else:
            self._begin_turn()
        return self._observation_vector(), float(reward), terminated, False, self._info(invalid)

    def action_masks(self) -> np.ndarray:
        """The candidate slots of this turn (what sb3-contrib's MaskablePPO asks for)."""
        return self._running()[1].mask.copy()

    def render(self):
        if self.render_mode != "ansi":
            return None
        if not self._last:
            return "no turn played yet"
        action = self._last["action"]
        return (f"turn {self._last['turn']}: {action['kind']} {self._last.get('question', '')} -> accuracy "
                f"{self._last['accuracy']:.3f}, budget left {self._last['budget_left']:g}").replace("  ", " ")

    def close(self) -> None:
        if self.manager is not None:
            self.manager.transcript.close()
            self.manager = None

    # -- the episode ----------------------------------------------------------------------
    def _dataset_option(self, options) -> int | None:
        """``reset(options={"dataset": k})`` plays training data set k (default: the seed mod datasets)."""
        if options is None:
            return None
        if not isinstance(options, dict) or set(options) - set(RESET_OPTIONS):
            raise SettingsError(f"reset options must be a dict with the keys {', '.join(RESET_OPTIONS)} (or None), "
                                f"got {options!r}")
        dataset = options.get("dataset")
        if dataset is not None and (isinstance(dataset, bool) or not isinstance(dataset, int | np.integer)
                                    or not 0 <= dataset < self.settings.datasets):
            raise SettingsError(f"reset option 'dataset' must be a whole number 0..{self.settings.datasets - 1} "
                                f"(the environment's training data sets), got {dataset!r}")
        return None if dataset is None else int(dataset)

    @property
    def records(self) -> list[dict]:
        """This episode's transcript records so far (the header first) when it is kept in memory."""
        transcript = None if self.manager is None else self.manager.transcript
        return list(transcript.records) if isinstance(transcript, MemoryTranscript) else []

    def _begin_turn(self) -> None:
        manager = self._running(started=False)[0]
        self._turn_start = manager.begin_turn()
        self._observation = self.layout.encode(manager.state, self.engine)

    def _running(self, started: bool = True) -> tuple[DialogManager, Observation]:
        if self.manager is None or (started and self._observation is None):
            raise SettingsError("call reset() before step(); an episode ended by the time allocation needs a reset")
        return self.manager, self._observation  # type: ignore[return-value]

    def _observation_vector(self) -> np.ndarray:
        return self._running()[1].vector.copy()

    def _info(self, invalid: bool) -> dict:
        manager, observation = self._running()
        return {"action_mask": observation.mask.copy(), "accuracy": self._accuracy, "turn": manager.turn,
                "spent": manager.state.spent, "budget": manager.state.budget, "invalid_action": invalid,
                "features": FEATURE_NAMES, "allocation": self.allocation.record()}


if ENV_ID not in gym.registry:
    gym.register(id=ENV_ID, entry_point="dialog.rl.gym_env:QuestioningEnv")
