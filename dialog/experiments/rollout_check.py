"""Play the rollout check (issue 49; ``learning.irl.rollout_check``): weights beside the scripted expert.

Both play the same episodes (data set d, seed s: the same scenes, the same teacher) of the training allocation
(ch7-training's condition, thesis §7.4.1) on calibration data, in worker processes; each episode is deterministic
from its seeds (``dialog.manager.episode_generators``: numpy Generators). ``teachbot learn-weights --check WEIGHTS``
and every fit call :func:`run_check`.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

from dialog.experiments.episodes import EpisodeSpec
from dialog.experiments.irl_rollouts import training_condition
from dialog.experiments.provenance import REPOSITORY
from dialog.experiments.runner import run_locally
from dialog.user_weights import UserWeights, read_user_weights
from learning.decision.weights import PRESETS
from learning.errors import DataFileError, SettingsError
from learning.irl.rollout_check import CheckSettings, episode_rollout, episode_rows, judge
from learning.strategies import check_strategy_name, is_external

WEIGHTS_ACCEPTED = (f"a weights .toml file (as teachbot learn-weights writes it), a preset ({', '.join(PRESETS)}) or "
                    "another strategy name")


@dataclass(frozen=True)
class Checked:
    """What is checked: its name in the tables, the strategy the episodes build and the user's weights if any."""

    label: str
    strategy: str
    weights: UserWeights | None = None


def checked_strategy(text: str) -> Checked:
    """``--check WEIGHTS``: a weights file (``*.toml``), a preset name, or any strategy name ``--strategy`` takes."""
    if not is_external(text) and (text.endswith(".toml") or Path(text).is_file()):
        try:
            weights = read_user_weights(text)
        except DataFileError as error:
            raise SettingsError(f"--check {text}: {error}; accepted: {WEIGHTS_ACCEPTED}") from None
        return Checked(Path(text).name, "checked-weights", weights)
    try:
        return Checked(text, check_strategy_name(text))
    except SettingsError as error:
        raise SettingsError(f"--check {text}: neither a weights file nor a strategy ({error}); accepted: "
                            f"{WEIGHTS_ACCEPTED}") from None


def allocation_path(settings: CheckSettings) -> Path:
    path = Path(settings.allocation)
    return path if path.is_absolute() else REPOSITORY / path


def check_specs(settings: CheckSettings, checked: Checked, scratch: str) -> tuple[list[EpisodeSpec], dict]:
    """The expert's episodes then the checked strategy's, pairwise the same (data set, seed); and the allocation."""
    path = allocation_path(settings)
    if not path.is_file():
        raise SettingsError(f"{settings.source}: allocation {settings.allocation}: no suite file there")
    condition = training_condition(path)
    c = condition.condition
    c = replace(c, turns=settings.turns or c.turns,
                budget=c.budget if settings.budget is None else float(settings.budget),
                change_every=settings.change_every or c.change_every)
    specs = []
    for role, strategy, weights in (("expert", settings.expert, None),
                                    ("checked", checked.strategy, checked.weights)):
        for dataset in range(settings.datasets):
            for seed in settings.seeds:
                specs.append(EpisodeSpec(
                    suite="rollout-check", task=condition.task, kitchen=condition.kitchen, strategy=strategy,
                    condition=c, dataset=dataset, seed=seed, costs=condition.costs, teacher=condition.teacher,
                    transcript=str(Path(scratch) / f"{role}-d{dataset}-s{seed}.jsonl"),
                    plan=condition.plan, data_seed=settings.data_seed, weights=weights))
    allocation = {"suite": settings.allocation, "task": condition.task, "kitchen": condition.kitchen,
                  "budget": c.budget, "turns": c.turns, "change_every": c.change_every,
                  "data_seed": settings.data_seed, "datasets": settings.datasets, "seeds": list(settings.seeds),
                  "plan": dict(condition.plan)}
    return specs, allocation


def shown(path: str) -> str:
    """A path as the tables show it: relative to the repository when inside it."""
    try:
        return str(Path(path).resolve().relative_to(REPOSITORY))
    except ValueError:
        return path


def run_check(settings: CheckSettings, checked: Checked) -> dict:
    """Play both strategies' episodes and judge them; the result is plain data (JSON) with the verdict."""
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="teachbot-check-") as scratch:
        specs, allocation = check_specs(settings, checked, scratch)
        results = run_locally(specs, settings.workers, progress=False)
    turns = allocation["turns"]
    rollouts = [episode_rollout(r["series"], r["accuracy"], spec.seed, spec.dataset, turns, settings.spending_at)
                for spec, r in zip(specs, results)]
    half = len(rollouts) // 2
    verdict = judge(rollouts[half:], rollouts[:half], settings)
    return {"checked": checked.label, "weights": None if checked.weights is None else dict(checked.weights.values),
            "expert": settings.expert, "allocation": allocation, "spending_at": list(settings.spending_at),
            "settings": shown(settings.source), **verdict,
            "episodes": {"checked": episode_rows(rollouts[half:]), "expert": episode_rows(rollouts[:half])},
            "seconds": round(time.perf_counter() - started, 2)}


SHIP_RULE = "the fit's own choice of fit, and the rollout check of the weights it wrote (docs/irl.md)"


def ship_rule_record(result: dict | None) -> dict:
    """What a fit's report records (issue 49): {"ship_rule", "rollout_check"}; the rule's ``passes`` is None
    when the check was not run (``result`` None), else the check's verdict, with the check's summary beside it."""
    if result is None:
        return {"ship_rule": {"passes": None, "rule": SHIP_RULE, "why": "the rollout check was skipped"},
                "rollout_check": None}
    summary = {key: result[key] for key in ("checked", "passes", "criteria", "checked_summary", "expert_summary",
                                            "allocation", "settings", "seconds")}
    return {"ship_rule": {"passes": bool(result["passes"]), "rule": SHIP_RULE}, "rollout_check": summary}
