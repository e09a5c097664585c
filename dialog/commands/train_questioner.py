"""``teachbot train-questioner``: learn a questioning policy with masked PPO on teachbot/Questioning-v0.

The command parses its arguments and prints; dialog/rl/training.py trains and
learning/rl/policy_file.py writes the policy (TOML + NPZ, no pickle).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from dialog.commands._arguments import (
    add_kitchen_option,
    add_task_option,
    budget,
    positive_int,
    price,
    seed,
)
from dialog.commands._json import print_json
from dialog.output_paths import check_writable, file_argument, make_parent, writing
from learning.errors import OutputPathError, SettingsError


def register(commands) -> None:
    parser = commands.add_parser(
        "train-questioner", help="learn a questioning policy by reinforcement learning (masked PPO)",
        description="Train a masked PPO policy (stable-baselines3 + sb3-contrib, the rl extra) on the Gymnasium "
                    "environment teachbot/Questioning-v0: the dialog loop with a scripted teacher on cached kitchen "
                    "data sets. The defaults are the chapter-7 training condition (dialog/suites/ch7-training.toml). "
                    "Writes FILE.toml and FILE.npz; run the policy with --strategy rl:FILE.toml in demo, teach "
                    "and regress.")
    parser.add_argument("--out", type=file_argument, required=True, metavar="FILE.toml",
                        help="the policy file to write (its weights go beside it as FILE.npz)")
    parser.add_argument("--steps", type=positive_int, default=20_000, help="environment steps (turns) to train on "
                                                                          "(default 20000)")
    parser.add_argument("--envs", type=positive_int, default=None,
                        help="environments played in parallel worker processes (default: up to 2, one per core)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the episodes and of PPO (default 0)")
    condition = parser.add_argument_group("training condition (default: the ch7-training suite's)")
    add_task_option(condition, None, "prepare-lunch")
    add_kitchen_option(condition, None, "kitchen-1")
    condition.add_argument("--budget", type=budget, default=None, help="question budget (default 15)")
    condition.add_argument("--turns", type=positive_int, default=None, help="turns per episode (default 30)")
    condition.add_argument("--change-every", type=positive_int, default=None,
                           help="a new scene every N turns (default 10)")
    condition.add_argument("--allocations", nargs="?", const="dialog/data/rl-allocations.toml", default=None,
                           metavar="FILE.toml",
                           help="train across allocations: each episode draws its budget, turns and scene changes "
                                "from FILE's ranges and the policy sees them (default file: "
                                "dialog/data/rl-allocations.toml); not with --budget, --turns, --change-every")
    condition.add_argument("--objects", type=positive_int, default=None, metavar="N",
                           help="objects in a scene (default: the task's own size, 12; the thesis's pack-lunchbox "
                                "experiments use 55)")
    condition.add_argument("--data-seed", type=seed, default=None,
                           help="the data sets' seed (default 100, which no chapter-6/7 report uses)")
    condition.add_argument("--price", type=price, default=0.0,
                           help="reward lost per unit of budget spent (default 0: reward is accuracy gained)")
    condition.add_argument("--no-whatif", action="store_true",
                           help="observe only phi(s) and the mask, not each candidate's expected features")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the training")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from dialog.experiments.provenance import git_commit
    from dialog.rl.training import TrainingConfig, default_envs, require_rl, train
    from learning.rl.policy_file import save_policy

    if args.out.suffix != ".toml":
        raise OutputPathError(f"--out {args.out}: a questioner policy file must end in .toml")
    check_writable(args.out, "policy file")
    check_writable(args.out.with_suffix(".npz"), "policy weights")
    require_rl()
    env = {"task": args.task, "kitchen": args.kitchen, "budget": args.budget, "turns": args.turns,
           "change_every": args.change_every, "data_seed": args.data_seed,
           "whatif": not args.no_whatif, "price": args.price, "allocations": allocations_of(args),
           "objects_per_scene": args.objects}
    config = TrainingConfig(steps=args.steps, envs=args.envs or default_envs(), seed=args.seed,
                            env={k: v for k, v in env.items() if v is not None})
    print(f"training a questioner with masked PPO for {config.steps} steps on {config.envs} environment(s), "
          f"seed {config.seed}", flush=True)
    policy, summary = train(config, progress=not args.no_progress,
                            provenance={"commit": git_commit(), "price": args.price},
                            say=lambda text: print(text, flush=True))
    make_parent(args.out, "policy file")
    with writing(args.out, "policy file"):
        save_policy(args.out, policy, "written by teachbot train-questioner: a masked PPO questioning policy\n"
                                      "run it with --strategy rl:" + str(args.out))
    print(trained_words(summary, args.out))
    if args.json:
        print_json({"out": str(args.out), **summary})
    return 0


def trained_words(summary: dict, out: Path) -> str:
    """The last line: steps, episodes, time, final accuracy and the two files written, both with their folder."""
    return (f"{summary['steps']} steps, {summary['episodes']} episodes in {summary['seconds']:.0f} s (estimated "
            f"{summary['estimated_seconds']:.0f} s); {final_accuracy_words(summary)}; wrote {out} and "
            f"{out.with_suffix('.npz')}")


def final_accuracy_words(summary: dict) -> str:
    """"final accuracy of the last 50 training episodes 0.585", with the real count when fewer ended."""
    count, final = summary["final_accuracy_episodes"], summary["final_accuracy_last_50"]
    if not count:
        return "no training episode ended, so no final accuracy"
    last = "the one training episode" if count == 1 else \
        (f"all {count} training episodes" if count == summary["episodes"] else f"the last {count} training episodes")
    return f"final accuracy of {last} {final:.3f}"


def allocations_of(args: argparse.Namespace):
    """``--allocations FILE``: the ranges each training episode draws from (None: one allocation)."""
    if args.allocations is None:
        return None
    given = [f"--{name.replace('_', '-')}" for name in ("budget", "turns", "change_every")
             if getattr(args, name) is not None]
    if given:
        raise SettingsError(f"--allocations draws each episode's allocation; {', '.join(given)} would fix it: "
                            "give one or the other")
    from dialog.rl.allocations import DEFAULT_FILE, load_allocations

    path = DEFAULT_FILE if args.allocations == "dialog/data/rl-allocations.toml" else args.allocations
    return load_allocations(path)
