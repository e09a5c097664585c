"""``teachbot learn-weights``: DT-task-env weights from expert demonstrations by maximum-entropy IRL (thesis §7.3.2).

``--method imitation`` (default, issue 27): per-turn MaxEnt fits over three-way splits of the demonstrations and
random starts, each iterate kept by validation log-likelihood, judged by held-out imitation; the fit shipped is the
one a rule fixed in advance picks (learning.irl.imitation).
``--method trajectory``: the thesis's trajectory-level fit (eq. 7.7), the learner's feature counts from
rollouts of the real dialog loop in the training condition (dialog.experiments.irl_rollouts), the iterate kept by
the final accuracy of greedy episodes on validation seeds. ``--method per-turn``: the per-turn fits of
learning.irl.maxent, kept by agreement with held-out demonstrations.
``--check WEIGHTS`` (issue 49): no fit; play the weights beside the scripted expert and judge how they ask
(dialog.commands._rollout_check). Every fit runs that check on what it wrote: the ship rule requires it.
"""

from __future__ import annotations

import argparse
import sys
import time

from dialog.commands._arguments import positive_int, seed
from dialog.commands._json import print_json, strict_json
from dialog.commands._rollout_check import add_check_options, run_rollout_check
from dialog.experiments.provenance import git_commit
from dialog.output_paths import check_writable, file_argument, make_parent, writing
from dialog.printed_command import command_line
from dialog.user_weights import UserWeights
from learning.errors import OutputPathError, SettingsError

# Trajectory defaults: sized so that 100 iterations fit in about 10 minutes on a 2-core machine (docs/irl.md).
CHECK_OPTIONS = ("settings", "seeds", "datasets", "data_seed", "turns", "workers")  # --check-* (the rollout check)
ROLLOUTS_PER_ITERATION = 6
VALIDATION_EPISODES = 8
EVALUATE_EVERY = 2


def register(commands) -> None:
    parser = commands.add_parser(
        "learn-weights", help="learn the DT-task-env decision-feature weights from expert demonstrations (IRL)",
        description="Fit maximum-entropy IRL (thesis eq. 7.5-7.7) to expert questioning episodes and write a "
                    "weights file the DT strategies read. By default (--method imitation) per-turn MaxEnt fits "
                    "over splits of the demonstrations and random starts, judged by how well they imitate held-out "
                    "demonstrations; --method trajectory is the thesis's trajectory-level fit of eq. 7.7 (the "
                    "learner's feature counts from rollouts of the dialog loop), --method per-turn one per-turn fit.")
    parser.add_argument("--demos", default=None, metavar="DIR_OR_shipped",
                        help="a directory of .json/.npz demonstrations (teachbot expert --out), one such file, or "
                             "'shipped' (learning/irl/expert-demos); required to fit")
    parser.add_argument("--out", type=file_argument, default=None, metavar="FILE.toml",
                        help="the weights file to write; required to fit")
    parser.add_argument("--method", choices=("imitation", "trajectory", "per-turn"), default="imitation",
                        help="imitation (default): per-turn MaxEnt fits over --split-seeds x --fit-seeds, judged by "
                             "held-out imitation (docs/irl.md); trajectory: eq. 7.7 with rollouts of the dialog "
                             "loop; per-turn: one per-turn MaxEnt fit on the recorded candidates (see --policy)")
    parser.add_argument("--features", choices=("habits", "thesis"), default=None,
                        help="habits: the thesis's seven decision features and the expert-habit features; thesis: "
                             "the seven only (default: what the demonstrations record)")
    parser.add_argument("--iterations", type=positive_int, default=100,
                        help="at most this many optimiser iterations (default 100, thesis §7.4.1)")
    parser.add_argument("--seed", type=seed, default=0,
                        help="seed of the demonstration split and of the rollouts' sampling (default 0)")
    trajectory = parser.add_argument_group("trajectory fit (--method trajectory)")
    trajectory.add_argument("--train-episodes", type=positive_int, default=3, metavar="N",
                            help="demonstrations to train on (default 3, as the thesis); the rest are held out")
    trajectory.add_argument("--rollouts", type=positive_int, default=ROLLOUTS_PER_ITERATION, metavar="N",
                            help=f"learner episodes per iteration (default {ROLLOUTS_PER_ITERATION})")
    trajectory.add_argument("--validation-episodes", type=positive_int, default=VALIDATION_EPISODES, metavar="N",
                            help=f"greedy episodes on validation seeds that score an iterate (default "
                                 f"{VALIDATION_EPISODES})")
    trajectory.add_argument("--evaluate-every", type=positive_int, default=EVALUATE_EVERY, metavar="K",
                            help=f"score every K-th iterate and the last (default {EVALUATE_EVERY})")
    trajectory.add_argument("--select", choices=("likelihood", "accuracy"), default="likelihood",
                            help="keep the iterate with the best log-likelihood of the held-out demonstrations' "
                                 "choices (default; the IRL objective), or the best task accuracy of greedy episodes "
                                 "on the validation seeds (scored every --evaluate-every iterations)")
    trajectory.add_argument("--start", choices=("per-turn", "zero"), default="per-turn",
                            help="iteration 0: the per-turn MaxEnt fit of the training demonstrations (default), or "
                                 "w = 0 (the default before issue 15; the shipped dt-task-env weights)")
    trajectory.add_argument("--workers", type=positive_int, default=None,
                            help="local worker processes for the rollouts (default: cores)")
    trajectory.add_argument("--ray", metavar="ADDRESS", default=None,
                            help="play the rollouts on the Ray cluster at ADDRESS ('local' starts one here)")
    imitation = parser.add_argument_group("imitation fit (--method imitation)")
    imitation.add_argument("--split-seeds", type=seed, nargs="+", default=[0, 1, 2], metavar="N",
                           help="each seed splits the demonstrations into train / validation / held out "
                                "(default 0 1 2)")
    imitation.add_argument("--fit-seeds", type=seed, nargs="+", default=[0, 1, 2, 3, 4], metavar="N",
                           help="each seed draws a random start for every split (default 0 1 2 3 4)")
    imitation.add_argument("--report", type=file_argument, default=None, metavar="FILE.json",
                           help="also write every fit's scores and the baselines to this JSON file")
    per_turn = parser.add_argument_group("per-turn fit (--method per-turn)")
    per_turn.add_argument("--validation", type=positive_int, default=None, metavar="N",
                          help="episodes held out for validation (default: all but three, at least one)")
    per_turn.add_argument("--policy", choices=("gated", "softmax"), default="gated",
                          help="gated (default): ask-or-not, then which query, as the DT decides; softmax: one "
                               "softmax over every candidate (docs/irl.md)")
    parser.add_argument("--allow-degenerate", action="store_true",
                        help="write the weights even when they can never ask (all zero but remaining_time's), which "
                             "is otherwise refused: such a DT stays quiet every turn")
    parser.add_argument("--json", action="store_true", help="end with one JSON line: iterations, seconds, weights, "
                                                             "validation_agreement, the rollout check and the ship "
                                                             "rule; with --check, the check's result")
    add_check_options(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, output_stream=None) -> int:
    from learning.decision.weights_file import save_weights
    from learning.irl.learn import weights_comment

    out = output_stream or sys.stdout
    if getattr(args, "check", None) is not None:
        return check_only(args, out)
    if args.demos is None or args.out is None:
        raise SettingsError(f"{'--demos' if args.demos is None else '--out'} is required to fit weights (--demos "
                            "DIR_OR_shipped --out FILE.toml); to check weights without fitting, give --check WEIGHTS")
    if getattr(args, "no_check", False):
        given = [f"--check-{name.replace('_', '-')}" for name in CHECK_OPTIONS if getattr(args, f"check_{name}", None)]
        if given:
            raise SettingsError(f"{', '.join(given)} set(s) the rollout check, which --no-check skips; give one or "
                                "the other")
    if args.out.suffix != ".toml":
        raise OutputPathError(f"--out {args.out}: a weights file must end in .toml")
    method = getattr(args, "method", "per-turn")
    check_options(args, method)
    check_writable(args.out, "weights file")  # before the fit, which takes a while
    if getattr(args, "report", None) is not None:
        check_writable(args.report, "fit report")
    learned = {"trajectory": learn_trajectory, "per-turn": learn_per_turn, "imitation": learn_imitation}[method](
        args, out)
    unidentified = sorted(unidentified_features(learned))
    if unidentified:
        print(f"warning: the demonstrations cannot identify {', '.join(unidentified)} (equal on every candidate of "
              "every demonstrated turn): left at 0", file=sys.stderr, flush=True)
    fitted = UserWeights(str(args.out), tuple(learned.weights.as_dict().items()))
    if fitted.never_asks() and not getattr(args, "allow_degenerate", False):
        raise SettingsError(f"--out {args.out}: nothing written: the fit kept iteration "
                            f"{learned.weights.provenance.get('best_iteration')}, whose weights can never ask "
                            "(every weight but "
                            "remaining_time's is 0, so every turn ties with no query); fit with other options "
                            "(e.g. --method trajectory, more "
                            "--iterations), or write them anyway with --allow-degenerate")
    make_parent(args.out, "weights file")
    with writing(args.out, "weights file"):
        save_weights(args.out, learned.weights, weights_comment(learned))
    for name, value in learned.weights.as_dict().items():
        note = "  (unidentified: equal on every candidate)" if name in unidentified else ""
        print(f"  {name:<30} {value:>12.4f}{note}", file=out)
    print(f"wrote {args.out}", file=out)
    summary = {**learned.summary(), **ship_rule(args, out)}
    if getattr(args, "report", None) is not None:
        make_parent(args.report, "fit report")
        with writing(args.report, "fit report"):
            args.report.write_text(strict_json(summary, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.report}", file=out)
    fitted.warn_if_never_asks()
    if args.json:
        print_json(summary, file=out)
    return 1 if summary["ship_rule"]["passes"] is False else 0


def check_only(args: argparse.Namespace, out) -> int:
    """``--check WEIGHTS``: the rollout check alone; fit options are refused rather than ignored."""
    fit_options = [name for name, given in (("--demos", args.demos is not None), ("--out", args.out is not None),
                                            ("--no-check", getattr(args, "no_check", False)))
                   if given]
    if fit_options:
        raise SettingsError(f"--check WEIGHTS checks weights without fitting: {', '.join(fit_options)} do(es) not "
                            "apply (fit with --demos and --out; every fit runs the check on what it writes)")
    result = run_rollout_check(args, args.check, out, table=not args.json)
    if args.json:
        print_json(result, file=out)
    return 0 if result["passes"] else 1


def ship_rule(args: argparse.Namespace, out) -> dict:
    """The rollout check of the weights just written (issue 49), which the ship rule requires: {"ship_rule",
    "rollout_check"}; the ship rule's ``passes`` is None when the check was skipped (--no-check)."""
    from dialog.experiments.rollout_check import ship_rule_record

    if getattr(args, "no_check", False):
        print("ship rule: not judged (--no-check: the rollout check was skipped)", file=out, flush=True)
        return ship_rule_record(None)
    result = run_rollout_check(args, str(args.out), out)
    print(f"ship rule: {'passes' if result['passes'] else 'FAILS (its rollout check failed)'}", file=out, flush=True)
    return ship_rule_record(result)


def unidentified_features(learned) -> tuple[str, ...]:
    if hasattr(learned, "result"):
        return tuple(learned.result.unidentified_features)
    listed = learned.weights.provenance.get("unidentified_features", "none")
    return () if listed == "none" else tuple(name.strip() for name in listed.split(","))


def check_options(args: argparse.Namespace, method: str) -> None:
    """Options of the other method are refused rather than silently ignored."""
    trajectory_only = [("--ray", getattr(args, "ray", None) is not None),
                       ("--start", getattr(args, "start", "per-turn") != "per-turn"),
                       ("--select", getattr(args, "select", "likelihood") != "likelihood"),
                       ("--workers", getattr(args, "workers", None) is not None)]
    imitation_only = [("--split-seeds", getattr(args, "split_seeds", [0, 1, 2]) != [0, 1, 2]),
                      ("--fit-seeds", getattr(args, "fit_seeds", [0, 1, 2, 3, 4]) != [0, 1, 2, 3, 4]),
                      ("--report", getattr(args, "report", None) is not None)]
    per_turn_only = [("--validation", getattr(args, "validation", None) is not None),
                     ("--policy", getattr(args, "policy", "gated") != "gated")]
    given = {"trajectory": per_turn_only + imitation_only,
             "per-turn": trajectory_only + imitation_only,
             "imitation": trajectory_only + per_turn_only}[method]
    wrong = [name for name, present in given if present]
    if wrong:
        raise SettingsError(f"{', '.join(wrong)} do(es) not apply to --method {method}; see "
                            f"{command_line(['learn-weights', '--help'])} for the options of each method")


def learn_imitation(args: argparse.Namespace, out):
    from dialog.experiments.irl_rollouts import training_condition
    from learning.irl.learn import learn_imitation_weights

    features = getattr(args, "features", None) or "habits"
    context = {"commit": git_commit(), **training_condition().provenance()}
    learned = learn_imitation_weights(args.demos, tuple(args.split_seeds), tuple(args.fit_seeds), args.iterations,
                                      features, context)
    report = learned.report
    print(f"{len(learned.fits)} per-turn fits ({len(args.split_seeds)} splits x {len(args.fit_seeds)} starts x "
          f"softmax and gated) in {learned.seconds:.1f} s; kept: {report['policy']}, split seed "
          f"{report['kept']['split_seed']}, fit seed {report['kept']['fit_seed']} (the median by validation "
          "log-likelihood)", file=out)
    spread, kept = report["held_out_spread"], report["kept"]["held_out"]
    for name in ("exact_agreement", "ask_or_quiet_agreement", "action_kind_agreement", "log_likelihood"):
        print(f"  held out {name.replace('_', ' ')}: kept {kept[name]:.3f}; {report['policy']} fits "
              f"{spread[name]['min']:.3f}..{spread[name]['max']:.3f} (median {spread[name]['median']:.3f})", file=out)
    quiet = report["baselines_on_kept_held_out"]["always_quiet"]["exact_agreement"]
    uniform = report["baselines_on_kept_held_out"]["uniform_random"]["exact_agreement"]
    print(f"  beside it on the same held-out turns: always quiet {quiet:.3f}, uniform random {uniform:.3f}", file=out)
    return learned


def learn_per_turn(args: argparse.Namespace, out):
    from learning.irl.learn import learn_weights

    learned = learn_weights(args.demos, args.iterations, args.seed, args.validation, args.policy,
                            getattr(args, "features", None))
    result, provenance = learned.result, learned.weights.provenance
    print(f"{len(learned.train)} training episodes ({result.train_turns} turns with a choice), "
          f"{len(learned.validation)} validation ({result.validation_turns} turns); {result.iterations} iterations, "
          f"kept iteration {result.best_iteration}; fit {result.seconds:.2f} s, all {learned.seconds:.2f} s",
          file=out)
    print(f"agreement with the expert: training {result.train_agreement:.3f}, validation "
          f"{result.validation_agreement:.3f} (asks or stays quiet alike: "
          f"{provenance.get('validation_ask_or_quiet_agreement', float('nan')):.3f}, same kind of action: "
          f"{provenance.get('validation_action_kind_agreement', float('nan')):.3f})", file=out)
    return learned


def learn_trajectory(args: argparse.Namespace, out):
    from dialog.experiments.irl_rollouts import (
        RolloutPool,
        rollout_functions,
        training_condition,
        training_seed,
        validation_seeds,
    )
    from learning.irl.learn import learn_trajectory_weights
    from learning.irl.rollouts import FeatureMatchingConfig

    started = time.perf_counter()
    condition = training_condition()
    held_out = validation_seeds(args.validation_episodes)
    config = FeatureMatchingConfig(max_iterations=args.iterations, rollouts_per_iteration=args.rollouts,
                                   seed=args.seed, evaluate_every=args.evaluate_every, start=args.start,
                                   select={"likelihood": "log_likelihood"}.get(args.select, args.select))
    last_seed = training_seed(args.iterations, args.rollouts - 1, args.rollouts)
    context = {"commit": git_commit(), **condition.provenance(),
               "training_rollout_seeds": f"{training_seed(1, 0, args.rollouts)}-{last_seed}",
               "validation_seeds": f"{held_out[0]}-{held_out[-1]}"}
    c = condition.condition
    print(f"trajectory MaxEnt IRL (eq. 7.7): {condition.task}/{condition.kitchen}, budget {c.budget:g}, {c.turns} "
          f"turns, a change every {c.change_every}, data seed {condition.data_seed} ({condition.source}); "
          f"{args.rollouts} rollouts an iteration; kept by {args.select}"
          + (f" ({len(held_out)} validation episodes every {args.evaluate_every} iteration(s))"
             if args.select == "accuracy" else f" ({len(held_out)} validation episodes score the kept iterate)"),
          file=out, flush=True)
    best = {"score": None, "iteration": 0}

    def progress(record, seconds: float) -> None:
        if record.evaluation is not None and (best["score"] is None or record.evaluation > best["score"]):
            best.update(score=record.evaluation, iteration=record.iteration)
        scored = "" if record.evaluation is None else f", validation accuracy {record.evaluation:.3f}"
        gap = "" if record.iteration == 0 else f"gap {record.loss:.3f}, "
        agreement = record.validation_agreement if record.validation_agreement is not None else float("nan")
        print(f"iteration {record.iteration:>3}/{args.iterations}: {gap}held-out agreement {agreement:.3f}"
              f"{scored} (best {best['score'] or 0:.3f} at {best['iteration']}); {seconds:.0f} s",
              file=out, flush=True)

    with RolloutPool(args.workers, args.ray) as pool:
        context["rollouts_on"] = pool.where
        rollouts, evaluate = rollout_functions(condition, pool, args.seed, args.validation_episodes)
        learned = learn_trajectory_weights(args.demos, rollouts, evaluate, config, args.train_episodes, context,
                                           progress, getattr(args, "features", None))
    result, provenance = learned.result, learned.weights.provenance
    print(f"kept iteration {result.best_iteration} of {result.iterations}: validation accuracy "
          f"{provenance['validation_accuracy']:.3f}; on the {len(learned.validation)} held-out demonstration(s) "
          f"({result.validation_turns} turns) agreement {result.validation_agreement:.3f}, log-likelihood "
          f"{result.validation_log_likelihood:.3f} a turn; total {time.perf_counter() - started:.0f} s",
          file=out, flush=True)
    return learned
