"""The ``teachbot`` command line."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path

from dialog.environment import SimulatedKitchen
from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.teachers import OracleTeacher
from dialog.transcript import TranscriptWriter
from learning.strategies import STRATEGY_NAMES, make_strategy


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of at least 1, got {value}")
    return value


def _budget(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of cost units, got '{text}'") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"the budget can't be negative, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="teachbot", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser("demo", help="run one scripted teaching episode in the simulated kitchen")
    demo.add_argument("--seed", type=int, default=0, help="one seed for every random choice (default 0)")
    demo.add_argument("--turns", type=_positive_int, default=30, help="time allocation T in turns (default 30)")
    demo.add_argument("--budget", type=_budget, default=40.0, help="question budget B in cost units (default 40)")
    demo.add_argument("--change-every", type=_positive_int, default=5,
                      help="a new scene every r turns (default 5)")
    demo.add_argument("--strategy", default="active", choices=STRATEGY_NAMES,
                      help="questioning strategy (default active)")
    demo.add_argument("--task", default="pack-lunchbox", help="task data file name (default pack-lunchbox)")
    demo.add_argument("--kitchen", default="kitchen-1", help="kitchen data file name (default kitchen-1)")
    demo.add_argument("--transcript", type=Path, default=None,
                      help="transcript path (default runs/demo-<strategy>-seed<seed>.jsonl)")
    demo.add_argument("--json", action="store_true", help="end with one JSON line summarising the episode")
    return parser


def run_demo(args: argparse.Namespace) -> dict:
    config = EpisodeConfig(turns=args.turns, budget=args.budget, change_every=args.change_every, seed=args.seed)
    rngs = episode_generators(args.seed)
    transcript_path = args.transcript or Path("runs") / f"demo-{args.strategy}-seed{args.seed}.jsonl"
    environment = SimulatedKitchen(task=args.task, kitchen=args.kitchen, seed=args.seed)
    try:
        with TranscriptWriter(transcript_path) as transcript:
            manager = DialogManager(environment, OracleTeacher(rngs["teacher"]), make_strategy(args.strategy),
                                    config, transcript, rngs)
            result = manager.run()
    finally:
        environment.close()
    print(f"\nAccuracy on {args.task} held-out scenes: {result.accuracy:.1%} "
          f"(chance {1 / len(environment.concepts):.0%}); budget spent {result.budget_spent:g} of {args.budget:g}; "
          f"queries {result.queries}; {result.seconds:.1f} s. Transcript: {result.transcript}")
    return asdict(result)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "demo":
        try:
            summary = run_demo(args)
        except (ValueError, RuntimeError) as error:
            print(f"teachbot: {error}", file=sys.stderr)
            return 2
        if args.json:
            summary = {k: summary[k] for k in ("seed", "strategy", "turns", "budget_spent", "queries", "accuracy",
                                               "transcript", "seconds")}
            summary["queries"] = {k: summary["queries"][k] for k in ("label", "demo", "none")}
            print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
