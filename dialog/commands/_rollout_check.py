"""``teachbot learn-weights --check WEIGHTS`` and the check at the end of every fit (issue 49; docs/irl.md).

Its options override the counts and seeds of ``learning/irl/rollout-check.toml``; the table says per episode
and summarised how the weights and the scripted expert asked, then the three criteria and the verdict.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from dialog.commands._arguments import positive_int, seed
from learning.errors import SettingsError


def add_check_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group(
        "the rollout check (--check WEIGHTS, and at the end of every fit; learning/irl/rollout-check.toml)")
    group.add_argument("--check", metavar="WEIGHTS", default=None,
                       help="play WEIGHTS (a weights .toml file, a preset such as dt-task-env, or a strategy name) "
                            "in the training allocation beside the scripted expert on the same episodes and judge "
                            "how they ask (no fit): exit 0 pass, 1 fail, 2 bad input")
    group.add_argument("--no-check", action="store_true",
                       help="after a fit, skip the rollout check (the ship rule is then reported as not judged)")
    group.add_argument("--check-settings", type=Path, default=None, metavar="FILE.toml",
                       help="the check's settings file (default learning/irl/rollout-check.toml)")
    group.add_argument("--check-seeds", type=seed, nargs="+", default=None, metavar="N",
                       help="episode seeds (default: the settings file's, 31 32 33 34; never the demonstrations' 1-30)")
    group.add_argument("--check-datasets", type=positive_int, default=None, metavar="N",
                       help="data sets each seed is played on (default 5)")
    group.add_argument("--check-data-seed", type=seed, default=None, metavar="N",
                       help="the calibration data seed the data sets are rendered from (default 101; >= 101)")
    group.add_argument("--check-turns", type=positive_int, default=None, metavar="N",
                       help="a shorter allocation for a quick look (default: ch7-training's 30 turns)")
    group.add_argument("--check-workers", type=positive_int, default=None, metavar="N",
                       help="worker processes (default 2)")


def check_settings(args: argparse.Namespace):
    """The settings file with the command line's overrides; a bad value is one SettingsError."""
    from learning.irl.rollout_check import CHECK_FILE, load_check_settings

    settings = load_check_settings(args.check_settings or CHECK_FILE)
    try:
        return settings.overridden(seeds=tuple(args.check_seeds) if args.check_seeds else None,
                                   datasets=args.check_datasets, data_seed=args.check_data_seed,
                                   turns=args.check_turns, workers=args.check_workers)
    except ValueError as error:
        raise SettingsError(str(error).replace(str(settings.source), "the check's options", 1)) from None


def run_rollout_check(args: argparse.Namespace, weights: str, out, table: bool = True) -> dict:
    """Play the check of ``weights`` and print its table (``table``); returns the result."""
    from dialog.experiments.rollout_check import checked_strategy, run_check

    checked = checked_strategy(weights)
    settings = check_settings(args)
    result = run_check(settings, checked)
    if table:
        print("\n".join(check_table(result)), file=out, flush=True)
    return result


def _spent(values) -> str:
    return " / ".join(f"{v:g}" for v in values)


def check_table(result: dict) -> list[str]:
    """The human-readable table: every episode, the means, the criteria and the verdict."""
    from learning.irl.rollout_check import spending_turns

    a = result["allocation"]
    turns = spending_turns(result["spending_at"], a["turns"])
    lines = [f"Rollout check of {result['checked']} beside {result['expert']}: {a['task']}/{a['kitchen']}, budget "
             f"{a['budget']:g}, {a['turns']} turns, a new scene every {a['change_every']}; data seed {a['data_seed']}, "
             f"{a['datasets']} data set(s) x seeds {' '.join(map(str, a['seeds']))} = "
             f"{len(result['episodes']['checked'])} episodes each ({result['settings']}); {result['seconds']:.0f} s",
             "",
             f"| episode | strategy | first FSQ | label | demo | FSQ | quiet | spent by turn "
             f"{'/'.join(map(str, turns))} | end accuracy |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for ours, theirs in zip(result["episodes"]["checked"], result["episodes"]["expert"]):
        for name, e in ((result["expert"], theirs), (result["checked"], ours)):
            first = "none" if e["first_feature_turn"] is None else str(e["first_feature_turn"])
            c = e["counts"]
            lines.append(f"| d{e['dataset']} s{e['seed']} | {name} | {first} | {c['label']} | {c['demo']} | "
                         f"{c['feature']} | {c['none']} | {_spent(e['spent_at'])} | {e['accuracy']:.3f} |")
    by_turn = result["criteria"][0]["rule"].rsplit(" ", 1)[-1]
    lines += ["", f"| mean | FSQ by turn {by_turn} | first FSQ (where asked) | label | demo | FSQ | quiet | spent by "
              f"turn {'/'.join(map(str, turns))} | end accuracy |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, s in ((result["expert"], result["expert_summary"]), (result["checked"], result["checked_summary"])):
        q = s["questions"]
        first = "never" if s["first_feature_turn_mean"] is None else f"{s['first_feature_turn_mean']:.1f}"
        lines.append(f"| {name} | {100 * s['feature_query_share']:.0f} % | {first} | {q['label']:.1f} | "
                     f"{q['demo']:.2f} | {q['feature']:.2f} | {q['none']:.1f} | "
                     f"{' / '.join(f'{v:.1f}' for v in s['spent_at'])} | {s['accuracy']:.3f} ± "
                     f"{s['accuracy_error']:.3f} |")
    lines.append("")
    for letter, c in zip("abc", result["criteria"]):
        value = f"{100 * c['value']:.0f} % of episodes" if c["name"] == "feature_query_early" else f"{c['value']:+.3f}"
        lines.append(f"({letter}) {c['name'].replace('_', ' ')}: {value}; needs {c['rule']}: "
                     f"{'pass' if c['passes'] else 'FAIL'}")
    lines.append(f"rollout check: {'PASS' if result['passes'] else 'FAIL'}")
    return lines
