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
* ``learn_imitation_weights`` (issue 27): the per-turn fit over several three-way splits and random
  starts, each kept by validation log-likelihood, judged on held-out demonstrations by imitation
  (``learning.irl.imitation``); the fit shipped is the one a rule fixed in advance picks.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from learning.datafiles import MissingDataFileError
from learning.decision.features import FEATURE_NAMES
from learning.decision.habits import EXTENDED_FEATURE_NAMES
from learning.decision.weights_file import DecisionWeights
from learning.errors import DataFileError, SettingsError
from learning.irl.demonstrations import QuestioningEpisode, load_episode_dir, load_episodes
from learning.irl.policy import greedy_choice

if TYPE_CHECKING:
    from learning.irl.maxent import IrlResult  # torch: imported only when fitting

SHIPPED = "shipped"
SHIPPED_DEMOS = Path(__file__).resolve().parent / "expert-demos"
THESIS_TRAINING_EPISODES = 3


FEATURE_SETS = {"thesis": FEATURE_NAMES, "habits": EXTENDED_FEATURE_NAMES}  # --features: what a fit weighs


def load_demonstrations(spec: str | Path, features: str | None = None) -> list[QuestioningEpisode]:
    """Episodes from ``shipped``, a directory of .json/.npz files or one such file; clear errors otherwise.

    ``features`` ("thesis": the seven, "habits": the seven and the expert-habit features) keeps those columns;
    None keeps what the files record."""
    path = SHIPPED_DEMOS if str(spec) == SHIPPED else Path(spec)
    if not path.exists():
        raise MissingDataFileError(f"--demos {spec}: no such file or directory; give a directory of .json/.npz "
                                   "demonstration files, one such file, or the word 'shipped'")
    episodes = load_episode_dir(path) if path.is_dir() else load_episodes(path)
    names = tuple(episodes[0].feature_names)
    if names not in FEATURE_SETS.values():
        raise DataFileError(f"--demos {spec}: the demonstrations record the features {list(names)}; DT-task-env weighs "
                            f"{list(FEATURE_NAMES)} or {list(EXTENDED_FEATURE_NAMES)} (in that order)")
    if features is None or FEATURE_SETS[features] == names:
        return episodes
    if not set(FEATURE_SETS[features]) <= set(names):
        raise DataFileError(f"--demos {spec}: --features {features} needs demonstrations that record "
                            f"{', '.join(FEATURE_SETS[features])}; these record only the thesis's seven (record new "
                            "ones with scripts/make_expert_demos.py or teachbot expert)")
    from learning.irl.imitation import select_features

    return select_features(episodes, FEATURE_SETS[features])


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
                  n_validation: int | None = None, policy: str = "gated",
                  features: str | None = None) -> LearnedWeights:
    """Load, split (seeded), fit and package the weights with a [provenance] table (method maxent-irl).

    ``policy="gated"`` (default) fits the DT's own ask-or-not-then-which rule; ``"softmax"`` the plain
    per-turn softmax over all candidates (see ``learning.irl.maxent._TorchTurns``)."""
    started = time.perf_counter()
    from learning.irl.maxent import IrlConfig, fit_maxent_irl, split_episodes  # torch: only when fitting

    episodes = load_demonstrations(demos, features)
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
                             progress=None, features: str | None = None) -> LearnedWeights:
    """Trajectory-level MaxEnt IRL (eq. 7.7) on ``train_episodes`` demonstrations, the rest held out.

    ``rollouts(w, iteration, count)`` plays the learner's episodes, ``evaluate(w)`` scores an iterate on
    validation episodes (``learning.irl.rollouts.fit_feature_matching``); ``config`` is its
    FeatureMatchingConfig (its seed also picks the training demonstrations). ``context`` (training
    condition, seeds, commit, ...) goes into the provenance.
    """
    started = time.perf_counter()
    from learning.irl.maxent import split_episodes
    from learning.irl.rollouts import fit_feature_matching

    episodes = load_demonstrations(demos, features)
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
                  "select_by": SELECT_BY[config.select],
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


# what each FeatureMatchingConfig.select keeps, in the weights' provenance
SELECT_BY = {"log_likelihood": "mean log-likelihood of the held-out demonstrations' choices (eq. 7.5); the validation "
                           "seeds' accuracy is reported for the kept iterate",
             "accuracy": "mean final accuracy of greedy DT episodes on the validation seeds",
             "agreement": "agreement of greedy choices with the held-out demonstrations; the validation seeds' "
                          "accuracy is reported for the kept iterate"}


@dataclass(frozen=True)
class ImitationWeights:
    """The protocol's fits, the one shipped by the fixed rule, and the report beside it."""

    weights: DecisionWeights
    fits: list
    report: dict
    seconds: float

    def summary(self) -> dict:
        return {"seconds": round(self.seconds, 3), "weights": self.weights.as_dict(), **self.report}


def learn_imitation_weights(demos: str | Path, split_seeds=(0, 1, 2), fit_seeds=(0, 1, 2, 3, 4),
                            iterations: int = 100, features: str = "habits",
                            context: dict | None = None, signs=()) -> ImitationWeights:
    """Issue 27's protocol (``learning.irl.imitation``): per-turn MaxEnt fits over every split and fit seed, the
    shipped fit chosen by the fixed rule, and a report of every fit's held-out imitation beside the baselines
    (always quiet, uniform random) and the same protocol on the thesis's seven features. ``signs`` ((feature,
    +1 | -1) pairs, issue 39) constrain the fit's weights; the report then adds the same protocol without them."""
    started = time.perf_counter()
    from learning.irl.imitation import baseline_scores, fit_protocol, select_features, shipped_fit, spread

    episodes = load_demonstrations(demos, features)
    if len(episodes) < 3:
        raise DataFileError(f"--demos {demos}: the imitation fit splits the demonstrations three ways (train, "
                            f"validation, held out) and needs at least 3 episodes, got {len(episodes)}")
    fits = fit_protocol(episodes, split_seeds, fit_seeds, iterations=iterations, signs=signs)
    kept = shipped_fit(fits)
    chosen = [f for f in fits if f.policy == kept.policy]
    by_name = {e.name: e for e in episodes}
    held_out = [by_name[name] for name in kept.held_out]
    seven = None
    if features != "thesis":
        seven_fits = fit_protocol(select_features(episodes, FEATURE_NAMES), split_seeds, fit_seeds,
                                  iterations=iterations)
        seven_kept = shipped_fit(seven_fits)
        same_form = [f for f in seven_fits if f.policy == seven_kept.policy]
        seven = {"policy": seven_kept.policy, "held_out": spread(same_form),
                 "kept_held_out": seven_kept.held_out_scores}
    without_signs = None
    if signs:
        free_fits = fit_protocol(episodes, split_seeds, fit_seeds, iterations=iterations)
        free_kept = shipped_fit(free_fits)
        without_signs = {"policy": free_kept.policy, "weights": free_kept.weights.as_dict(),
                         "held_out": spread([f for f in free_fits if f.policy == free_kept.policy]),
                         "kept_held_out": free_kept.held_out_scores}
    report = {"features": list(episodes[0].feature_names), "policy": kept.policy,
              "signs": {name: (">= 0" if sign > 0 else "<= 0") for name, sign in signs},
              "kept": {"split_seed": kept.split_seed, "fit_seed": kept.fit_seed, "best_iteration": kept.best_iteration,
                       "validation": kept.validation_scores, "held_out": kept.held_out_scores},
              "held_out_spread": spread(chosen), "validation_spread": spread(chosen, "validation_scores"),
              "baselines_on_kept_held_out": baseline_scores(held_out),
              "baselines_spread": {name: {score: {"min": min(b[name][score] for b in bases),
                                                  "max": max(b[name][score] for b in bases)}
                                          for score in ("exact_agreement", "ask_or_quiet_agreement")}
                                   for bases in [[baseline_scores([by_name[n] for n in f.held_out]) for f in chosen]]
                                   for name in ("always_quiet", "uniform_random")},
              "thesis_features_per_turn_fit": seven, "same_features_without_signs": without_signs,
              "fits": [{"split_seed": f.split_seed, "fit_seed": f.fit_seed, "policy": f.policy,
                        "validation_log_likelihood": f.validation_scores["log_likelihood"],
                        **{f"held_out_{k}": v for k, v in f.held_out_scores.items()}} for f in fits]}
    provenance = {"method": "maxent-irl-per-turn-imitation", "policy": kept.policy, "optimizer": "lbfgs",
                  "select_iterate_by": "validation log-likelihood",
                  "ship_rule": "the policy form with the higher mean validation log-likelihood; the median of its "
                               "fits by validation log-likelihood",
                  "commit": (context or {}).get("commit", "unknown"),
                  "demos": SHIPPED if str(demos) == SHIPPED else str(demos),
                  "demonstrations": demonstration_files(demos),
                  **{k: v for k, v in (context or {}).items() if k != "commit"},
                  **({"signs": ", ".join(f"{n} {'>=' if v > 0 else '<='} 0" for n, v in signs)} if signs else {}),
                  "split_seeds": ", ".join(map(str, split_seeds)), "fit_seeds": ", ".join(map(str, fit_seeds)),
                  "kept_split_seed": kept.split_seed, "kept_fit_seed": kept.fit_seed,
                  "max_iterations": iterations, "best_iteration": kept.best_iteration,
                  "train_episodes": ", ".join(kept.train), "validation_episodes": ", ".join(kept.validation),
                  "held_out_episodes": ", ".join(kept.held_out),
                  **{f"validation_{k}": round(v, 6) for k, v in kept.validation_scores.items() if k != "turns"},
                  **{f"held_out_{k}": round(v, 6) for k, v in kept.held_out_scores.items() if k != "turns"},
                  "unidentified_features": ", ".join(kept.unidentified) or "none"}
    weights = DecisionWeights(kept.weights.feature_names, kept.weights.values, provenance)
    return ImitationWeights(weights, fits, report, time.perf_counter() - started)


def weights_comment(learned: LearnedWeights) -> str:
    if isinstance(learned, ImitationWeights):
        return ("DT-task-env weights (thesis eq. 7.2) learned by per-turn maximum-entropy IRL (eq. 7.5-7.7) from the "
                "scripted expert's demonstrations,\nover three-way splits and random starts, each kept by validation "
                "log-likelihood; the fit a rule fixed in advance picks. Written by `teachbot learn-weights`; "
                "docs/irl.md.")
    if learned.weights.provenance.get("method") == "maxent-irl-trajectory":
        return (f"DT-task-env weights (thesis eq. 7.2) learned by trajectory-level maximum-entropy IRL (eq. 7.7) "
                f"from {len(learned.train)} expert episodes,\nthe iterate whose greedy episodes did best on the "
                f"validation seeds. Written by `teachbot learn-weights`; docs/irl.md.")
    return (f"DT-task-env weights (thesis eq. 7.2) learned by maximum-entropy IRL (eq. 7.5-7.7) from "
            f"{len(learned.train)} expert episodes,\nthe iterate best on {len(learned.validation)} held-out "
            f"episode(s). Written by `teachbot learn-weights`; docs/irl.md.")
