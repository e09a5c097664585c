"""``teachbot learn-weights``: DT-task-env weights from expert demonstrations (thesis §7.3.2, §7.4.1).

Load the demonstrations (a directory of .json/.npz files, one file, or the
shipped ones in learning/irl/expert-demos/) and hold out whole episodes
(three train, as in the thesis; the rest are held out). Two fits:

* ``learn_trajectory_weights`` (the default of ``teachbot learn-weights``): the
  thesis's trajectory-level MaxEnt IRL (eq. 7.7, ``learning.irl.rollouts``) with
  rollouts and validation episodes supplied by the caller (the dialog loop:
  dialog.experiments.irl_rollouts); the iterate best on the validation episodes
  is kept, agreement and likelihood on the held-out demonstrations reported.
* ``learn_weights``: per-turn MaxEnt IRL (``learning.irl.maxent``), kept by
  agreement with the held-out demonstrations.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from learning.datafiles import MissingDataFileError
from learning.decision.features import FEATURE_NAMES
from learning.decision.weights_file import DecisionWeights
from learning.errors import DataFileError, SettingsError
from learning.irl.demonstrations import QuestioningEpisode, load_episode_dir, load_episodes
from learning.irl.policy import greedy_choice

if TYPE_CHECKING:
    from learning.irl.maxent import IrlResult  # torch: imported only when fitting

SHIPPED = "shipped"
SHIPPED_DEMOS = Path(__file__).resolve().parent / "expert-demos"
THESIS_TRAINING_EPISODES = 3


def load_demonstrations(spec: str | Path) -> list[QuestioningEpisode]:
    """Episodes from ``shipped``, a directory of .json/.npz files or one such file; clear errors otherwise."""
    path = SHIPPED_DEMOS if str(spec) == SHIPPED else Path(spec)
    if not path.exists():
        raise MissingDataFileError(f"--demos {spec}: no such file or directory; give a directory of .json/.npz "
                                   "demonstration files, one such file, or the word 'shipped'")
    episodes = load_episode_dir(path) if path.is_dir() else load_episodes(path)
    names = episodes[0].feature_names
    if tuple(names) != FEATURE_NAMES:
        raise DataFileError(f"--demos {spec}: the demonstrations record the features {list(names)}; DT-task-env weighs "
                            f"{list(FEATURE_NAMES)} (in that order)")
    return episodes


def default_validation_count(n_episodes: int) -> int:
    """All but three episodes validate (the thesis trained on three); at least one does."""
    if n_episodes < 2:
        raise DataFileError(f"learning weights needs at least 2 demonstration episodes (one to train, one to "
                            f"validate), got {n_episodes}")
    return max(1, n_episodes - THESIS_TRAINING_EPISODES)


def decision_agreement(episodes, weights: np.ndarray) -> dict[str, float]:
    """Beyond exact agreement: how often w asks when the expert asks (or keeps quiet when it does), and picks the
    same kind of action (label, demo, feature, none), over the turns with a choice."""
    same_ask, same_kind, counted = 0, 0, 0
    for episode in episodes:
        for turn in episode.turns:
            if turn.n_actions < 2 or turn.kinds is None:
                continue
            ours = greedy_choice(turn, weights)
            counted += 1
            same_ask += (turn.kinds[ours] == "none") == (turn.kinds[turn.chosen] == "none")
            same_kind += turn.kinds[ours] == turn.kinds[turn.chosen]
    if not counted:
        return {}
    return {"ask_or_quiet_agreement": same_ask / counted, "action_kind_agreement": same_kind / counted}


@dataclass(frozen=True)
class LearnedWeights:
    weights: DecisionWeights
    result: IrlResult
    train: list
    validation: list
    seconds: float  # loading, splitting and fitting

    def summary(self) -> dict:
        """The last stdout line of ``teachbot learn-weights``."""
        return {"iterations": self.result.iterations, "seconds": round(self.seconds, 3),
                "weights": self.weights.as_dict(), "validation_agreement": self.result.validation_agreement}


def learn_weights(demos: str | Path, iterations: int = 100, seed: int = 0,
                  n_validation: int | None = None, policy: str = "gated") -> LearnedWeights:
    """Load, split (seeded), fit and package the weights with a [provenance] table (method maxent-irl).

    ``policy="gated"`` (default) fits the DT's own ask-or-not-then-which rule; ``"softmax"`` the plain
    per-turn softmax over all candidates (see ``learning.irl.maxent._TorchTurns``)."""
    started = time.perf_counter()
    from learning.irl.maxent import IrlConfig, fit_maxent_irl, split_episodes  # torch: only when fitting

    episodes = load_demonstrations(demos)
    n_validation = default_validation_count(len(episodes)) if n_validation is None else n_validation
    if n_validation < 1:  # the kept iterate is the best on validation: there must be some
        raise SettingsError(f"n_validation must be at least 1 (weights are kept by validation agreement), "
                            f"got {n_validation}")
    train, validation = split_episodes(episodes, n_validation, np.random.default_rng(seed))
    result = fit_maxent_irl(train, validation, IrlConfig(max_iterations=iterations, seed=seed, policy=policy))
    assert result.validation_agreement is not None, "n_validation >= 1 gives validation episodes"
    fitted = result.weights.provenance
    diagnostics = decision_agreement(validation, result.weights.values)
    provenance = {"method": "maxent-irl", "variant": fitted["method"], "policy": fitted["policy"],
                  "optimizer": fitted["optimizer"],
                  "l2": fitted["l2"], "select_by": fitted["select_by"],
                  "demos": SHIPPED if str(demos) == SHIPPED else str(demos),
                  "train_episodes": ", ".join(e.name for e in train),
                  "validation_episodes": ", ".join(e.name for e in validation), "seed": seed,
                  "max_iterations": iterations, "iterations": result.iterations,
                  "best_iteration": result.best_iteration, "train_turns": result.train_turns,
                  "train_agreement": round(result.train_agreement, 6),
                  "validation_turns": result.validation_turns,
                  "validation_agreement": round(result.validation_agreement, 6),
                  **{f"validation_{key}": round(value, 6) for key, value in diagnostics.items()},
                  "unidentified_features": ", ".join(result.unidentified_features) or "none"}
    weights = DecisionWeights(result.weights.feature_names, result.weights.values, provenance)
    return LearnedWeights(weights, result, train, validation, time.perf_counter() - started)


def demonstration_files(spec: str | Path) -> str:
    """The demonstration file names behind ``--demos`` (for the provenance)."""
    path = SHIPPED_DEMOS if str(spec) == SHIPPED else Path(spec)
    if path.is_dir():
        return ", ".join(sorted(p.name for p in path.iterdir() if p.suffix in (".json", ".npz") and p.is_file()))
    return path.name


def learn_trajectory_weights(demos: str | Path, rollouts, evaluate, config,
                             train_episodes: int = THESIS_TRAINING_EPISODES, context: dict | None = None,
                             progress=None) -> LearnedWeights:
    """Trajectory-level MaxEnt IRL (eq. 7.7) on ``train_episodes`` demonstrations, the rest held out.

    ``rollouts(w, iteration, count)`` plays the learner's episodes, ``evaluate(w)`` scores an iterate on
    validation episodes (``learning.irl.rollouts.fit_feature_matching``); ``config`` is its
    FeatureMatchingConfig (its seed also picks the training demonstrations). ``context`` (training
    condition, seeds, commit, ...) goes into the provenance.
    """
    started = time.perf_counter()
    from learning.irl.maxent import split_episodes
    from learning.irl.rollouts import fit_feature_matching

    episodes = load_demonstrations(demos)
    if isinstance(train_episodes, bool) or not isinstance(train_episodes, int) or not 1 <= train_episodes < len(
            episodes):
        raise SettingsError(f"--train-episodes must be in 1..{len(episodes) - 1} (at least one of the "
                            f"{len(episodes)} demonstrations is held out), got {train_episodes!r}")
    train, held_out = split_episodes(episodes, len(episodes) - train_episodes, np.random.default_rng(config.seed))
    result = fit_feature_matching(train, rollouts, held_out, config, evaluate=evaluate, progress=progress)
    kept = result.history[result.best_iteration]
    assert kept.evaluation is not None and result.validation_agreement is not None, \
        "the kept iterate was evaluated and there are held-out demonstrations"
    assert result.validation_log_likelihood is not None, "held-out demonstrations give a likelihood"
    diagnostics = decision_agreement(held_out, result.weights.values)
    provenance = {"method": "maxent-irl-trajectory",
                  "gradient": "eq. 7.7: expert minus rollout feature counts per turn",
                  "optimizer": "adam", "learning_rate": config.learning_rate, "l2": config.l2,
                  "start": result.weights.provenance["start"],
                  "select_by": "mean final accuracy of greedy DT episodes on the validation seeds",
                  "commit": (context or {}).get("commit", "unknown"),
                  "demos": SHIPPED if str(demos) == SHIPPED else str(demos),
                  "demonstrations": demonstration_files(demos),
                  "train_episodes": ", ".join(e.name for e in train),
                  "held_out_episodes": ", ".join(e.name for e in held_out), "seed": config.seed,
                  **{k: v for k, v in (context or {}).items() if k != "commit"},
                  "rollouts_per_iteration": config.rollouts_per_iteration, "evaluate_every": config.evaluate_every,
                  "max_iterations": config.max_iterations, "iterations": result.iterations,
                  "best_iteration": result.best_iteration, "validation_accuracy": round(kept.evaluation, 6),
                  "held_out_turns": result.validation_turns,
                  "held_out_agreement": round(result.validation_agreement, 6),
                  "held_out_log_likelihood": round(result.validation_log_likelihood, 6),
                  **{f"held_out_{key}": round(value, 6) for key, value in diagnostics.items()},
                  "train_agreement": round(result.train_agreement, 6),
                  "unidentified_features": ", ".join(result.unidentified_features) or "none"}
    weights = DecisionWeights(result.weights.feature_names, result.weights.values, provenance)
    return LearnedWeights(weights, result, train, held_out, time.perf_counter() - started)


def weights_comment(learned: LearnedWeights) -> str:
    if learned.weights.provenance.get("method") == "maxent-irl-trajectory":
        return (f"DT-task-env weights (thesis eq. 7.2) learned by trajectory-level maximum-entropy IRL (eq. 7.7) "
                f"from {len(learned.train)} expert episodes,\nthe iterate whose greedy episodes did best on the "
                f"validation seeds. Written by `teachbot learn-weights`; docs/irl.md.")
    return (f"DT-task-env weights (thesis eq. 7.2) learned by maximum-entropy IRL (eq. 7.5-7.7) from "
            f"{len(learned.train)} expert episodes,\nthe iterate best on {len(learned.validation)} held-out "
            f"episode(s). Written by `teachbot learn-weights`; docs/irl.md.")
