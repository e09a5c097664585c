"""``teachbot learn-weights``: DT-task-env weights from expert demonstrations by maximum-entropy IRL (thesis §7.3.2)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from dialog.commands._arguments import positive_int
from dialog.output_paths import check_writable, writing
from learning.errors import OutputPathError


def register(commands) -> None:
    parser = commands.add_parser(
        "learn-weights", help="learn the DT-task-env decision-feature weights from expert demonstrations (IRL)",
        description="Fit maximum-entropy IRL (thesis eq. 7.5-7.7) to expert questioning episodes and write a "
                    "weights file the DT strategies read. Episodes are split into training and validation; the "
                    "iterate with the best validation agreement is kept.")
    parser.add_argument("--demos", required=True, metavar="DIR_OR_shipped",
                        help="a directory of .json/.npz demonstrations (teachbot expert --out), one such file, or "
                             "'shipped' (learning/irl/expert-demos)")
    parser.add_argument("--out", type=Path, required=True, metavar="FILE.toml", help="the weights file to write")
    parser.add_argument("--iterations", type=positive_int, default=100,
                        help="at most this many optimiser iterations (default 100, thesis §7.4.1)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the training/validation split (default 0)")
    parser.add_argument("--validation", type=positive_int, default=None, metavar="N",
                        help="episodes held out for validation (default: all but three, at least one)")
    parser.add_argument("--policy", choices=("gated", "softmax"), default="gated",
                        help="gated (default): ask-or-not, then which query, as the DT decides; softmax: one "
                             "softmax over every candidate (docs/irl.md)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line: iterations, seconds, weights, "
                                                             "validation_agreement")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, output_stream=None) -> int:
    from learning.decision.weights_file import save_weights
    from learning.irl.learn import learn_weights, weights_comment

    out = output_stream or sys.stdout
    if args.out.suffix != ".toml":
        raise OutputPathError(f"--out {args.out}: a weights file must end in .toml")
    if not args.out.parent.exists():
        raise OutputPathError(f"--out {args.out}: the directory {args.out.parent} does not exist")
    check_writable(args.out, "weights file")  # before the fit, which takes a while
    learned = learn_weights(args.demos, args.iterations, args.seed, args.validation, args.policy)
    with writing(args.out, "weights file"):
        save_weights(args.out, learned.weights, weights_comment(learned))
    result, provenance = learned.result, learned.weights.provenance
    print(f"{len(learned.train)} training episodes ({result.train_turns} turns with a choice), "
          f"{len(learned.validation)} validation ({result.validation_turns} turns); {result.iterations} iterations, "
          f"kept iteration {result.best_iteration}; fit {result.seconds:.2f} s, all {learned.seconds:.2f} s",
          file=out)
    print(f"agreement with the expert: training {result.train_agreement:.3f}, validation "
          f"{result.validation_agreement:.3f} (asks or stays quiet alike: "
          f"{provenance.get('validation_ask_or_quiet_agreement', float('nan')):.3f}, same kind of action: "
          f"{provenance.get('validation_action_kind_agreement', float('nan')):.3f})", file=out)
    for name, value in learned.weights.as_dict().items():
        note = "  (unidentified: equal on every candidate)" if name in result.unidentified_features else ""
        print(f"  {name:<30} {value:>12.4f}{note}", file=out)
    print(f"wrote {args.out}", file=out)
    if args.json:
        print(json.dumps(learned.summary()), file=out, flush=True)
    return 0
