"""Make the shipped expert demonstrations (learning/irl/expert-demos/) with the scripted expert.

The thesis's training condition (§7.4.1), read from the ``ch7-training`` suite (dialog/suites/ch7-training.toml:
prepare-lunch, budget 15, 30 turns, a scene change every 10 turns, costs DQ 2, FSQ 2, LQ 1, NQ 0), played as
the suite's episodes are: on the cached data sets rendered from the suite's data seed (100, which the ch7 suite
never uses), demonstration seed s on training pool s mod datasets with episode seed 1000 s + pool, the same
loop and scripted teacher as `teachbot regress` and IRL's rollouts. One episode per seed; by default seeds 1-30,
which `teachbot learn-weights --method imitation` splits three ways (train / validation / held out; docs/irl.md).
Every turn records the thesis's seven decision features and the expert-habit features (learning.decision.habits).
Reproducible: every random choice comes from the episode seed. The transcripts go to --transcripts (not
shipped). --clear removes the old demonstration files in --out first.

    .venv/bin/python scripts/make_expert_demos.py [--seeds 1 2 ... 30] [--data-seed N] [--suite NAME]
        [--out DIR] [--transcripts DIR] [--clear] [--json]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dialog.experiments.episodes import EpisodeSpec  # noqa: E402
from dialog.experiments.pools import PoolEnvironment, load_pools  # noqa: E402
from dialog.experiments.suite import load_suite  # noqa: E402
from dialog.expert.episode import ExpertSettings, run_expert_episode  # noqa: E402
from dialog.expert.scripted import ScriptedExpertChooser  # noqa: E402
from learning.irl.learn import SHIPPED_DEMOS  # noqa: E402

DEFAULT_SEEDS = tuple(range(1, 31))


def episode_spec(suite, seed: int, data_seed: int) -> EpisodeSpec:
    """The suite's first condition for demonstration seed ``seed``: pool seed mod datasets, as IRL's rollouts."""
    return EpisodeSpec(suite=suite.name, task=suite.task, kitchen=suite.kitchen, strategy="scripted-expert",
                       condition=suite.conditions[0], dataset=seed % suite.datasets, seed=seed,
                       costs=tuple(sorted(suite.costs.items())), teacher=tuple(sorted(suite.teacher.items())),
                       transcript="", plan=suite.plan_options, data_seed=data_seed)


def make_demo(spec: EpisodeSpec, scratch: Path):
    """One scripted-expert episode on the spec's pools; returns the expert outcome."""
    teacher = dict(spec.teacher)
    if set(teacher) - {"mislabel_rate", "dont_know_rate"} or teacher.get("kind", "scripted") != "scripted":
        raise SystemExit(f"make_expert_demos: the suite's teacher {teacher} is not a scripted teacher with "
                         "mislabel_rate / dont_know_rate only")
    pools = load_pools(spec.task, spec.kitchen, spec.dataset + 1, spec.plan, data_seed=spec.data_seed)
    c = spec.condition
    environment = PoolEnvironment(pools.train[spec.dataset], pools.test, pools.task, -(-c.turns // c.change_every))
    settings = ExpertSettings(task=spec.task, kitchen=spec.kitchen, seed=spec.episode_seed, turns=c.turns,
                              budget=c.budget, change_every=c.change_every, costs=dict(spec.costs),
                              mislabel_rate=teacher.get("mislabel_rate", 0.0),
                              dont_know_rate=teacher.get("dont_know_rate", 0.0))
    name = f"{ScriptedExpertChooser.name}-{spec.task}-seed{spec.seed}"
    where = {"environment": "data sets (cached pools)", "suite": spec.suite, "data_seed": spec.data_seed,
             "dataset": spec.dataset, "demonstration_seed": spec.seed, "episode_seed": spec.episode_seed}
    return run_expert_episode(settings, ScriptedExpertChooser(), scratch, environment, say=lambda text: None,
                              name=name, metadata=where)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(DEFAULT_SEEDS))
    parser.add_argument("--suite", default="ch7-training", help="the suite whose first condition is played")
    parser.add_argument("--data-seed", type=int, default=None, help="data sets from this seed (default: the suite's)")
    parser.add_argument("--out", type=Path, default=SHIPPED_DEMOS)
    parser.add_argument("--transcripts", type=Path, default=None, help="keep the transcripts here (default: dropped)")
    parser.add_argument("--clear", action="store_true", help="remove the demonstration files in --out first")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if any(seed < 0 for seed in args.seeds) or (args.data_seed is not None and args.data_seed < 0):
        parser.error("seeds and the data seed must be whole numbers >= 0")
    suite = load_suite(args.suite)
    data_seed = suite.data_seed if args.data_seed is None else args.data_seed
    started_all = time.perf_counter()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.clear:
        for old in args.out.glob("*.json"):
            old.unlink()
    scratch = Path(tempfile.mkdtemp(prefix="expert-demos-"))
    summary = []
    try:
        for seed in args.seeds:
            started = time.perf_counter()
            spec = episode_spec(suite, seed, data_seed)
            outcome = make_demo(spec, scratch)
            target = args.out / outcome.demonstration.name
            shutil.copyfile(outcome.demonstration, target)
            if args.transcripts is not None:
                args.transcripts.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(outcome.transcript, args.transcripts / outcome.transcript.name)
            row = {"seed": seed, "dataset": spec.dataset, "episode_seed": spec.episode_seed,
                   "file": str(target.relative_to(ROOT) if target.is_relative_to(ROOT) else target),
                   "accuracy": round(outcome.result.accuracy, 4), "budget_spent": outcome.result.budget_spent,
                   "queries": outcome.result.queries, "seconds": round(time.perf_counter() - started, 2)}
            summary.append(row)
            print(f"seed {seed} (pool {spec.dataset}, data seed {data_seed}): {row['queries']}, spent "
                  f"{row['budget_spent']:g}, accuracy {row['accuracy']:.3f}, {row['seconds']:.1f} s -> {row['file']}")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    seconds = time.perf_counter() - started_all
    print(f"{len(summary)} demonstrations in {seconds:.1f} s")
    if args.json:
        print(json.dumps({"episodes": summary, "data_seed": data_seed, "seconds": round(seconds, 2)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
