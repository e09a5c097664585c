"""``teachbot expert``: play the robot's questioner; every turn is saved as an IRL demonstration (thesis §7.3.2)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dialog.commands._arguments import add_kitchen_option, add_task_option, budget, positive_int, seed
from dialog.commands._json import print_json
from dialog.commands._summary import questions_in_words
from dialog.expert.episode import ExpertSettings
from learning.actions import DEFAULT_COSTS

COST_NAMES = {"lq": "label", "label": "label", "dq": "demo", "demo": "demo", "fsq": "feature", "feature": "feature",
              "nq": "none", "none": "none"}


def costs(text: str) -> dict:
    """'DQ=2,FSQ=2,LQ=1,NQ=0' (any of LQ/DQ/FSQ/NQ or label/demo/feature/none; missing ones keep the default)."""
    table = dict(DEFAULT_COSTS)
    for part in filter(None, (p.strip() for p in text.split(","))):
        name, _, value = part.partition("=")
        kind = COST_NAMES.get(name.strip().lower())
        if kind is None or not value:
            raise argparse.ArgumentTypeError(f"'{part}': expected NAME=NUMBER with NAME one of LQ, DQ, FSQ, NQ")
        table[kind] = budget(value.strip())
    return table


def register(commands) -> None:
    parser = commands.add_parser(
        "expert", help="play the robot's questioner: pick its questions; the turns become IRL demonstrations",
        description="Each turn shows the scene and every candidate question with its cost and its seven expected "
                    "decision features; you pick one (LQ 4, DQ fruit, FSQ, none; help, quit) and a scripted teacher "
                    "answers. The feature columns: ACD classifier discriminability, CDU class-distribution "
                    "uniformity, IV instance variation, PM prediction margin, budget (fraction spent), time "
                    "(fraction of turns left), quiet (time since the last question); 'help' in a session explains "
                    "each. Defaults are the thesis's training condition (§7.4.1).")
    defaults = ExpertSettings()
    add_task_option(parser, defaults.task)
    add_kitchen_option(parser, defaults.kitchen)
    parser.add_argument("--budget", type=budget, default=defaults.budget,
                        help=f"query budget (default {defaults.budget:g})")
    parser.add_argument("--turns", type=positive_int, default=defaults.turns, help=f"turns (default {defaults.turns})")
    parser.add_argument("--change-every", type=positive_int, default=defaults.change_every,
                        help=f"a new scene every r turns (default {defaults.change_every})")
    parser.add_argument("--costs", type=costs, default=dict(defaults.costs), metavar="DQ=2,FSQ=2,LQ=1,NQ=0",
                        help="query costs (default DQ 2, FSQ 2, LQ 1, NQ 0)")
    parser.add_argument("--seed", type=seed, default=defaults.seed,
                        help=f"one seed for every random choice (default {defaults.seed})")
    parser.add_argument("--out", type=Path, default=Path("runs") / "expert", metavar="DIR",
                        help="directory for the demonstration (.json) and the transcript (.jsonl)")
    parser.add_argument("--expert", choices=("person", "scripted"), default="person",
                        help="who chooses: you (default) or the scripted expert")
    parser.add_argument("--json", action="store_true", help="end with one JSON line summarising the episode")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, input_stream=None, output_stream=None) -> int:
    from dialog.environment import SimulatedKitchen
    from dialog.expert.episode import ExpertQuit, output_paths, run_expert_episode
    from dialog.expert.scripted import ScriptedExpertChooser
    from dialog.expert.terminal import PersonChooser

    out = output_stream or sys.stdout
    settings = ExpertSettings(task=args.task, kitchen=args.kitchen, budget=args.budget, turns=args.turns,
                              change_every=args.change_every, seed=args.seed, costs=args.costs)
    settings.config()  # check the allocation before building the kitchen
    chooser_name = "person" if args.expert == "person" else ScriptedExpertChooser.name
    output_paths(args.out, settings.name(chooser_name))
    environment = SimulatedKitchen(task=settings.task, kitchen=settings.kitchen, seed=settings.seed)
    try:
        if args.expert == "person":
            chooser = PersonChooser(input_stream, out, environment.locations, environment.viewpoint)
            say, observers = chooser.say, (chooser,)
            say(f"Expert mode: '{settings.task}' ({', '.join(environment.concepts)}) in {settings.kitchen}, "
                f"{settings.turns} turns, budget {settings.budget:g}, a new scene every {settings.change_every}. "
                "You choose the robot's questions; a scripted teacher answers. Type 'help' for the commands.")
        else:
            chooser = ScriptedExpertChooser()
            say, observers = (lambda text: print(text, file=out, flush=True)), ()
        try:
            outcome = run_expert_episode(settings, chooser, args.out, environment, say=say, observers=observers)
        except ExpertQuit as stop:
            print(f"Nothing saved: {stop}", file=out, flush=True)
            return 0
    finally:
        environment.close()
    result = outcome.result
    turns = len(outcome.episode.turns)
    print(f"{'Stopped' if result.quit else 'Done'} after {turns} turn{'' if turns == 1 else 's'}: accuracy "
          f"{result.accuracy:.1%}, budget spent {result.budget_spent:g} of {settings.budget:g}; "
          f"{questions_in_words(result.queries)}. Demonstration: {outcome.demonstration}; "
          f"transcript: {outcome.transcript}",
          file=out, flush=True)
    if args.json:
        print_json({"seed": settings.seed, "expert": chooser.name, "turns": len(outcome.episode.turns),
                          "quit": result.quit, "budget_spent": result.budget_spent, "queries": result.queries,
                          "accuracy": round(result.accuracy, 6), "demonstration": str(outcome.demonstration),
                          "transcript": str(outcome.transcript)}, file=out)
    return 0
