"""The rollout check of learned weights (issue 49): how they ask, beside the expert they imitate (thesis §7.4.1).

Per-turn likelihood and agreement (eq. 7.5-7.7, ``learning.irl.imitation``) score a fit one turn at a time on the
expert's own states; they never see where the fit's own choices lead. The rollout check plays the weights (DT,
eq. 7.1) and the scripted expert on the same episodes of the training allocation and compares, per episode, the
turn of the first feature question, the questions of each kind, the budget spent by fractions of the allocation
and the end accuracy. It passes when (a) the feature question comes within ``feature_query_by_turn`` turns in at
least ``feature_query_share`` of the weights' episodes, (b) their mean demonstrations per episode are within
``demo_difference`` of the expert's and (c) their mean end accuracy is within ``accuracy_difference`` of the
expert's. The numbers live in ``rollout-check.toml``; this module is the arithmetic on plain per-turn series.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from learning.datafiles import check_keys, integer, number, numbers, read_toml, section, text

CHECK_FILE = Path(__file__).resolve().parent / "rollout-check.toml"
KINDS = ("label", "demo", "feature", "none")
DEMONSTRATION_SEEDS = range(1, 31)  # the shipped expert demonstrations' episode seeds (learning/irl/expert-demos)


@dataclass(frozen=True)
class CheckSettings:
    """Where the check plays (``[episodes]``), when it reads the spending curve and its pass thresholds."""

    allocation: str  # a suite file (relative to the repository) whose first condition is the allocation
    expert: str
    data_seed: int
    datasets: int
    seeds: tuple[int, ...]
    workers: int
    spending_at: tuple[float, ...]
    feature_query_by_turn: int
    feature_query_share: float
    demo_difference: float
    accuracy_difference: float
    turns: int | None = None  # None: the allocation's; a shorter one for a quick look (tests)
    budget: float | None = None
    change_every: int | None = None
    source: str = str(CHECK_FILE)

    @property
    def episodes(self) -> int:
        return self.datasets * len(self.seeds)

    def overridden(self, **changes) -> CheckSettings:
        """These settings with the given fields replaced (None leaves a field as it is), checked again."""
        settings = replace(self, **{k: v for k, v in changes.items() if v is not None})
        settings.check()
        return settings

    def check(self) -> None:
        where = self.source
        if self.data_seed < 101:
            raise ValueError(f"{where}: the check plays on calibration data, data seed >= 101 (100 holds the "
                             f"demonstrations, 0-99 the reported tables); got {self.data_seed}")
        reused = sorted(set(self.seeds) & set(DEMONSTRATION_SEEDS))
        if reused:
            raise ValueError(f"{where}: episode seed {reused[0]} is one of the expert demonstrations' seeds 1-30; "
                             "choose seeds outside 1-30 (e.g. 31 and up)")
        if not self.seeds or any(s < 0 for s in self.seeds) or len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"{where}: seeds must be distinct whole numbers >= 0, got {list(self.seeds)}")
        for name in ("datasets", "workers"):
            if getattr(self, name) < 1:
                raise ValueError(f"{where}: {name} must be a whole number >= 1, got {getattr(self, name)}")
        if self.turns is not None and self.turns < 1:
            raise ValueError(f"{where}: turns must be a whole number >= 1, got {self.turns}")
        if self.budget is not None and not (math.isfinite(self.budget) and self.budget >= 0):
            raise ValueError(f"{where}: budget must be a number >= 0, got {self.budget}")


def load_check_settings(path: str | Path = CHECK_FILE) -> CheckSettings:
    """The check's settings from its TOML file; a bad file is one DataFileError naming the field."""
    data = read_toml(path, "rollout check settings")
    where = str(path)
    check_keys(data, where, required=("episodes", "spending", "pass"))
    episodes = section(data, "episodes", where)
    check_keys(episodes, f"{where} [episodes]", required=("allocation", "expert", "data_seed", "datasets", "seeds",
                                                          "workers"))
    spending = section(data, "spending", where)
    check_keys(spending, f"{where} [spending]", required=("at",))
    rule = section(data, "pass", where)
    check_keys(rule, f"{where} [pass]", required=("feature_query_by_turn", "feature_query_share", "demo_difference",
                                                  "accuracy_difference"))
    e, r = f"{where} [episodes]", f"{where} [pass]"
    settings = CheckSettings(
        allocation=text(episodes, "allocation", e), expert=text(episodes, "expert", e),
        data_seed=integer(episodes, "data_seed", e, low=0), datasets=integer(episodes, "datasets", e, low=1),
        seeds=tuple(int(s) for s in numbers(episodes, "seeds", e, whole=True, low=0)),
        workers=integer(episodes, "workers", e, low=1),
        spending_at=numbers(spending, "at", f"{where} [spending]", above=0, high=1),
        feature_query_by_turn=integer(rule, "feature_query_by_turn", r, low=1),
        feature_query_share=number(rule, "feature_query_share", r, low=0, high=1),
        demo_difference=number(rule, "demo_difference", r, low=0),
        accuracy_difference=number(rule, "accuracy_difference", r, low=0, high=1), source=where)
    try:
        settings.check()
    except ValueError as error:
        from learning.errors import DataFileError

        raise DataFileError(str(error)) from None
    return settings


@dataclass(frozen=True)
class EpisodeRollout:
    """How one episode asked: the first feature question's turn (None: never), questions per kind (``KINDS``,
    "none" = quiet turns), the budget spent by each spending point and the end accuracy."""

    seed: int
    dataset: int
    turns: int
    first_feature_turn: int | None
    counts: dict[str, int]
    spent_at: tuple[float, ...]
    accuracy: float


def spending_turns(spending_at: Sequence[float], turns: int) -> list[int]:
    """The turns the spending curve is read at: ceil(f turns) for every fraction f, at least turn 1."""
    return [max(1, math.ceil(f * turns - 1e-9)) for f in spending_at]


def episode_rollout(series: dict[str, Sequence], accuracy: float, seed: int, dataset: int, turns: int,
                    spending_at: Sequence[float]) -> EpisodeRollout:
    """One episode's figures from its per-turn cumulative series (``dialog.experiments.episodes.SERIES``).

    ``turns`` is the allocation; a spending point f reads the budget spent by the end of turn ceil(f turns)
    (the last turn played, if the episode ended sooner)."""
    played = len(series["turn"])
    if played == 0:
        raise ValueError("an episode with no turns has no rollout figures")
    features = list(series["feature"])
    first = next((int(series["turn"][i]) for i, n in enumerate(features) if n >= 1), None)
    counts = {kind: int(series[kind][-1]) for kind in KINDS[:3]}
    counts["none"] = played - int(series["questions"][-1])
    spent = [float(series["spent"][min(played, t) - 1]) for t in spending_turns(spending_at, turns)]
    return EpisodeRollout(int(seed), int(dataset), played, first, counts, tuple(spent), float(accuracy))


def summarise(episodes: Sequence[EpisodeRollout], by_turn: int) -> dict:
    """Means over episodes: questions per kind, the spending curve and end accuracy; the share of episodes
    whose first feature question comes by turn ``by_turn`` and the mean turn of it where it comes."""
    if not episodes:
        raise ValueError("no episodes to summarise")
    firsts = [e.first_feature_turn for e in episodes]
    asked = [t for t in firsts if t is not None]
    return {"episodes": len(episodes),
            "feature_query_share": float(np.mean([t is not None and t <= by_turn for t in firsts])),
            "feature_query_never": sum(t is None for t in firsts),
            "first_feature_turn_mean": float(np.mean(asked)) if asked else None,
            "questions": {kind: float(np.mean([e.counts[kind] for e in episodes])) for kind in KINDS},
            "spent_at": [float(v) for v in np.mean([e.spent_at for e in episodes], axis=0)],
            "accuracy": float(np.mean([e.accuracy for e in episodes])),
            "accuracy_error": float(np.std([e.accuracy for e in episodes], ddof=1) / np.sqrt(len(episodes)))
            if len(episodes) > 1 else 0.0}


def judge(checked: Sequence[EpisodeRollout], expert: Sequence[EpisodeRollout], settings: CheckSettings) -> dict:
    """The check's verdict: both summaries and each criterion (value, what it is held to, passes)."""
    ours, theirs = summarise(checked, settings.feature_query_by_turn), summarise(expert, settings.feature_query_by_turn)
    demo_gap = ours["questions"]["demo"] - theirs["questions"]["demo"]
    accuracy_gap = ours["accuracy"] - theirs["accuracy"]
    criteria = [
        {"name": "feature_query_early", "value": ours["feature_query_share"],
         "rule": f">= {settings.feature_query_share:g} of episodes ask FSQ by turn {settings.feature_query_by_turn}",
         "passes": bool(ours["feature_query_share"] >= settings.feature_query_share - 1e-12)},
        {"name": "demonstrations", "value": demo_gap,
         "rule": f"|mean demos - expert's| <= {settings.demo_difference:g}",
         "passes": bool(abs(demo_gap) <= settings.demo_difference + 1e-12)},
        {"name": "end_accuracy", "value": accuracy_gap,
         "rule": f"|mean end accuracy - expert's| <= {settings.accuracy_difference:g}",
         "passes": bool(abs(accuracy_gap) <= settings.accuracy_difference + 1e-12)},
    ]
    return {"passes": all(c["passes"] for c in criteria), "criteria": criteria, "checked_summary": ours,
            "expert_summary": theirs}


def episode_rows(episodes: Sequence[EpisodeRollout]) -> list[dict]:
    """The per-episode figures as plain data (JSON)."""
    return [asdict(e) | {"spent_at": list(e.spent_at)} for e in episodes]
