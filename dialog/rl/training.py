"""Training a questioner with masked PPO on ``teachbot/Questioning-v0`` (``teachbot train-questioner``).

sb3-contrib's MaskablePPO (the ``rl`` extra) learns a policy over the
environment's action slots, never choosing a masked one. The defaults, fixed
before any chapter-7 comparison: the chapter-7 training condition
(dialog/rl/gym_env.py), the actor and critic each an MLP of two tanh layers of 64
(stable-baselines3's default), gamma 1 (the episode's return is then the final
held-out accuracy gain, the quantity the thesis compares), GAE lambda 0.95,
rollouts of 256 steps per environment, minibatches of 64, 10 epochs, learning
rate 3e-4. The trained actor is written as a policy file without pickle
(learning/rl/policy_file.py) that ``--strategy rl:FILE`` runs with numpy alone.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from learning.errors import SettingsError, SetupError
from learning.limits import check_limit
from learning.rl.observation import ObservationLayout
from learning.rl.policy_file import QuestionerPolicy

HIDDEN = (64, 64)
ESTIMATE_EPISODES, ESTIMATE_TURNS = 2, 60  # timed before training for the time estimate: at least this many of each
# across allocations each episode draws its own, and a turn's cost varies several-fold between draws: two draws
# said 117 s for a run that took 863 s (docs/rl.md), so the probe plays more of them
ESTIMATE_EPISODES_ACROSS = 8


@dataclass(frozen=True)
class TrainingConfig:
    """What ``train-questioner`` fits: environment options, PPO's settings, the number of steps and the seed."""

    steps: int = 20_000
    envs: int = 2
    seed: int = 0
    env: dict = field(default_factory=dict)  # QuestioningEnv options: task, budget, turns, change_every, ...
    n_steps: int = 256
    batch_size: int = 64
    epochs: int = 10
    learning_rate: float = 3e-4
    gamma: float = 1.0
    gae_lambda: float = 0.95

    def __post_init__(self) -> None:
        for name in ("steps", "envs", "n_steps", "batch_size", "epochs"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise SettingsError(f"{name} must be a whole number of 1 or more, got {value!r}")
        check_limit("training_steps", self.steps, "steps")
        check_limit("workers", self.envs, "envs")
        for name, low, high in (("learning_rate", 0.0, 1.0), ("gamma", 0.0, 1.0), ("gae_lambda", 0.0, 1.0)):
            value = getattr(self, name)
            if not isinstance(value, int | float) or isinstance(value, bool) or not low < value <= high:
                raise SettingsError(f"{name} must be a number in ({low:g}, {high:g}], got {value!r}")


def require_rl():
    """sb3-contrib's MaskablePPO, or a one-line SetupError naming the extra to install."""
    try:
        import gymnasium  # noqa: F401
        from sb3_contrib import MaskablePPO
    except ImportError:
        raise SetupError("training a questioner needs the rl extra: pip install -e '.[rl]' (gymnasium, "
                         "stable-baselines3, sb3-contrib)") from None
    return MaskablePPO


def make_env(options: dict):
    """A factory for one environment (what the vector environment starts in each worker)."""
    def build():
        from dialog.rl.gym_env import QuestioningEnv
        return QuestioningEnv(**options)
    return build


class _Progress:
    """Steps done, episodes ended, the mean final accuracy of the last 20 episodes and the time, on standard error."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.enabled, self.started = total, enabled, time.perf_counter()
        self.accuracies: list[float] = []
        self.episodes = 0
        self.restated = False  # whether the estimate was said again after the first rollout
        self._bar = self._task = None

    def __enter__(self):
        if self.enabled:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            console = Console(file=sys.stderr)
            self._bar = Progress(TextColumn("training steps"), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn(),
                                 TextColumn("{task.description}"), console=console,
                                 transient=not console.is_terminal)
            self._bar.start()
            self._task = self._bar.add_task("", total=self.total)
        return self

    def update(self, steps: int, infos, dones) -> None:
        for info, done in zip(infos, dones):
            if done:
                self.episodes += 1
                self.accuracies.append(float(info["accuracy"]))
        if self._bar is not None:
            recent = self.accuracies[-20:]
            text = f"{self.episodes} episodes" + (f", final accuracy {np.mean(recent):.3f} (last {len(recent)})"
                                                  if recent else "")
            self._bar.update(self._task, completed=min(steps, self.total), description=text)

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.stop()


def train(config: TrainingConfig, progress: bool = True, provenance: dict | None = None, say=None):
    """Train; returns (the policy, a summary dict with the seconds, episodes and recent accuracy). ``say`` (a
    function of one line) hears what is being done before each slow step (data sets, workers, training)."""
    say = say or (lambda text: None)
    MaskablePPO = require_rl()
    import torch
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    torch.set_num_threads(1)
    started = time.perf_counter()
    say("loading the training data sets (rendered in the simulated kitchen on the first run, then cached)...")
    probe = make_env(config.env)()  # validates the options here, once, and renders the data sets if needed
    layout = probe.layout
    loading = time.perf_counter() - started  # the training environments load the same data sets again
    probe_episodes = ESTIMATE_EPISODES if probe.allocations is None else ESTIMATE_EPISODES_ACROSS
    per_turn = seconds_per_turn(probe, config.seed, episodes=probe_episodes)
    probe.close()
    so_far = time.perf_counter() - started
    estimate = so_far + loading + per_turn * config.steps / min(config.envs, os.cpu_count() or 1)
    say(f"this will take about {_duration(estimate)} in all: {so_far:.0f} s so far, {loading:.0f} s to start the "
        "environments, then "
        f"{config.steps} steps at {per_turn * 1000:.0f} ms per turn over {config.envs} environment(s) (timed on "
        f"{probe_episodes}+ whole episodes of random questions)")
    say(f"starting {config.envs} environment{'s' if config.envs > 1 else ''}"
        f"{' in worker processes' if config.envs > 1 else ''}, then training...")
    vec_cls = SubprocVecEnv if config.envs > 1 else DummyVecEnv
    vec_kwargs = {"start_method": "spawn"} if config.envs > 1 else None
    venv = make_vec_env(make_env(config.env), n_envs=config.envs, seed=config.seed, vec_env_cls=vec_cls,
                        vec_env_kwargs=vec_kwargs)
    tracker = _Progress(config.steps, progress)

    class Track(BaseCallback):
        def _on_step(self) -> bool:
            tracker.update(self.num_timesteps, self.locals["infos"], self.locals["dones"])
            return True

        def _on_rollout_start(self) -> None:
            if tracker.restated or not self.num_timesteps or self.num_timesteps >= config.steps:
                return
            tracker.restated = True  # once, after the first rollout and its update: a real policy's turns timed
            spent = time.perf_counter() - training_started
            left = spent * (config.steps - self.num_timesteps) / self.num_timesteps
            say(f"after the first {self.num_timesteps} steps ({spent:.0f} s): about {_duration(left)} left")

    try:
        model = MaskablePPO("MlpPolicy", venv, n_steps=config.n_steps, batch_size=config.batch_size,
                            n_epochs=config.epochs, learning_rate=config.learning_rate, gamma=config.gamma,
                            gae_lambda=config.gae_lambda, seed=config.seed, device="cpu", verbose=0,
                            policy_kwargs={"net_arch": {"pi": list(HIDDEN), "vf": list(HIDDEN)}})
        training_started = time.perf_counter()
        with tracker:
            model.learn(total_timesteps=config.steps, callback=Track())
    finally:
        venv.close()
    seconds = time.perf_counter() - started
    recent = tracker.accuracies[-50:]
    summary = {"steps": int(model.num_timesteps), "episodes": tracker.episodes, "seconds": round(seconds, 1),
               "estimated_seconds": round(estimate, 1),
               "final_accuracy_last_50": round(float(np.mean(recent)), 4) if recent else None,
               "final_accuracy_episodes": len(recent)}
    record = {**(provenance or {}), **{f"ppo_{k}": v for k, v in asdict(config).items() if k != "env"},
              **{f"env_{k}": _plain(v) for k, v in probe.settings.__dict__.items() if v is not None},
              "env_objects_per_scene": probe.objects_per_scene,
              **(probe.allocations.record() if probe.allocations is not None else {}),
              "algorithm": "MaskablePPO (sb3-contrib)", "hidden_layers": list(HIDDEN), **summary}
    return actor_policy(model, layout, record), summary


def seconds_per_turn(env, seed: int, episodes: int = ESTIMATE_EPISODES, turns: int = ESTIMATE_TURNS) -> float:
    """Wall seconds per environment step over whole episodes of uniformly random candidate slots (what an
    untrained masked policy plays): at least ``episodes`` episodes and ``turns`` turns, resets included, since a
    turn's cost grows with the examples learned and so with the episode's allocation and its progress."""
    rng = np.random.default_rng(seed)
    started, played, ended = time.perf_counter(), 0, 0
    while ended < episodes or played < turns:
        _, info = env.reset(seed=seed + ended)
        terminated = False
        while not terminated:
            _, _, terminated, _, info = env.step(int(rng.choice(np.flatnonzero(info["action_mask"]))))
            played += 1
        ended += 1
    return (time.perf_counter() - started) / played


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min"


def actor_policy(model, layout: ObservationLayout, provenance: dict) -> QuestionerPolicy:
    """The actor of a MaskablePPO model as a numpy policy: the policy network's linear layers, then the action head."""
    policy = model.policy
    linears = [m for m in policy.mlp_extractor.policy_net if hasattr(m, "weight")] + [policy.action_net]
    weights = tuple(m.weight.detach().cpu().numpy().astype(np.float64) for m in linears)
    biases = tuple(m.bias.detach().cpu().numpy().astype(np.float64) for m in linears)
    activations = {type(m).__name__ for m in policy.mlp_extractor.policy_net if not hasattr(m, "weight")}
    if activations != {"Tanh"}:
        raise RuntimeError(f"the policy network uses {activations}; the policy file records tanh")
    return QuestionerPolicy(layout, weights, biases, "tanh", {k: _plain(v) for k, v in provenance.items()})


def _plain(value):
    """A provenance value TOML can hold: dicts become 'k v, ...' text."""
    if isinstance(value, dict):
        return ", ".join(f"{k} {v}" for k, v in sorted(value.items())) or "none"
    if value is None:
        return "none"
    return value


def default_envs() -> int:
    return max(1, min(2, os.cpu_count() or 1))
