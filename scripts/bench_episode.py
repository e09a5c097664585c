"""Benchmark: one scripted teaching episode with pointing, headless, through the real dialog manager.

    python scripts/bench_episode.py                      # 60 turns, active strategy, seed 0
    python scripts/bench_episode.py --pictures --json    # also write numbered pictures; JSON last line
    python scripts/bench_episode.py --noise-study 10     # accuracy cost of 10 % mislabels over seeds 0..9

The episode is real: PyBullet scenes rendered and measured, the arm moving for
every label query, the scripted teacher's answers written as text and read by
the parser, a transcript synced every turn. The wall time is split into the
kitchen's construction, the held-out test set, and the episode's turns (of which
pointing, scene changes and the strategy's choices are timed separately).
Goal: the 60-turn episode (turns only) within 10 s on the 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from dialog.environment import SimulatedKitchen
from dialog.episode import build_episode
from dialog.manager import episode_generators
from dialog.settings import EpisodeSettings
from dialog.teachers.scripted import ScriptedTeacher
from dialog.transcripts.jsonl import TranscriptWriter

GOAL_SECONDS = 10.0


class Timed:
    """Wraps an object and adds up the wall time of the named methods."""

    def __init__(self, inner, methods):
        self._inner, self.seconds, self.calls = inner, {m: 0.0 for m in methods}, {m: 0 for m in methods}
        for method in methods:
            setattr(self, method, self._wrap(method))

    def _wrap(self, method):
        original = getattr(self._inner, method)

        def timed(*args, **kwargs):
            started = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.seconds[method] += time.perf_counter() - started
                self.calls[method] += 1
        return timed

    def __getattr__(self, name):
        return getattr(self._inner, name)


def run_episode(args, seed: int, mislabel_rate: float, folder: Path) -> dict:
    started = time.perf_counter()
    kitchen = SimulatedKitchen(task=args.task, kitchen=args.kitchen, seed=seed, pictures=args.pictures)
    built = time.perf_counter()
    environment = Timed(kitchen, ("point_at", "next_scene", "test_set", "fetch"))
    settings = EpisodeSettings(task=args.task, kitchen=args.kitchen, strategy=args.strategy, seed=seed,
                               turns=args.turns, budget=args.budget, change_every=args.change_every)
    strategy = Timed(settings.build_strategy(), ("choose",))
    strategy.name = args.strategy
    pictures = str(folder / f"pictures-{seed}") if args.pictures else None
    rngs = episode_generators(seed)
    teacher = ScriptedTeacher(rngs["teacher"], mislabel_rate=mislabel_rate)
    try:
        with TranscriptWriter(folder / f"episode-{seed}-{mislabel_rate}.jsonl") as transcript:
            manager = build_episode(settings, environment, teacher, transcript, strategy=strategy, rngs=rngs,
                                    say=lambda _: None, pictures=pictures)
            manager.begin()
            began, began_cpu = time.perf_counter(), time.process_time()
            result = manager.run()
            finished, finished_cpu = time.perf_counter(), time.process_time()
    finally:
        kitchen.close()
    return {
        "seed": seed, "strategy": args.strategy, "turns": args.turns, "mislabel_rate": mislabel_rate,
        "accuracy": round(result.accuracy, 4), "queries": result.queries, "mislabels": teacher.mislabels,
        "pointings": environment.calls["point_at"], "scenes": environment.calls["next_scene"],
        "seconds": {
            "build": round(built - started, 3), "test_set": round(environment.seconds["test_set"], 3),
            "turns": round(finished - began, 3), "turns_cpu": round(finished_cpu - began_cpu, 3),
            "pointing": round(environment.seconds["point_at"], 3),
            "scene_changes": round(environment.seconds["next_scene"], 3),
            "strategy": round(strategy.seconds["choose"], 3), "total": round(finished - started, 3),
        },
    }


def benchmark(args) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        runs = [run_episode(args, seed, args.mislabel_rate, Path(folder)) for seed in range(args.seed,
                                                                                              args.seed + args.repeat)]
    turns = [r["seconds"]["turns"] for r in runs]
    cpu = [r["seconds"]["turns_cpu"] for r in runs]
    for run in runs:
        s = run["seconds"]
        print(f"seed {run['seed']}: {run['turns']} turns in {s['turns']:.2f} s ({s['turns_cpu']:.2f} s CPU; "
              f"pointing {run['pointings']}x "
              f"{s['pointing']:.2f} s, {run['scenes']} scene changes {s['scene_changes']:.2f} s, strategy "
              f"{s['strategy']:.2f} s); build {s['build']:.2f} s, test set {s['test_set']:.2f} s; accuracy "
              f"{run['accuracy']:.3f}")
    summary = {"benchmark": "episode", "strategy": args.strategy, "turns": args.turns, "pictures": args.pictures,
               "turn_seconds_median": round(float(np.median(turns)), 3),
               "turn_cpu_seconds_median": round(float(np.median(cpu)), 3), "goal_seconds": GOAL_SECONDS,
               "within_goal": bool(np.median(turns) <= GOAL_SECONDS), "runs": runs}
    print(f"median {summary['turn_seconds_median']:.2f} s ({summary['turn_cpu_seconds_median']:.2f} s CPU) for "
          f"{args.turns} turns (goal <= {GOAL_SECONDS:g} s): "
          f"{'met' if summary['within_goal'] else 'missed'}")
    return summary


def noise_study(args) -> dict:
    """Accuracy with a perfect teacher and with ``--study-rate`` mislabels, paired by seed (same scenes)."""
    from scipy.stats import wilcoxon

    pairs = []
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(args.seed, args.seed + args.noise_study):
            clean = run_episode(args, seed, 0.0, Path(folder))
            noisy = run_episode(args, seed, args.study_rate, Path(folder))
            pairs.append((clean["accuracy"], noisy["accuracy"], noisy["mislabels"]))
            print(f"seed {seed}: oracle {clean['accuracy']:.3f}, {args.study_rate:.0%} mislabels "
                  f"{noisy['accuracy']:.3f} ({noisy['mislabels']} wrong answers)")
    clean, noisy, wrong = (np.array(column, dtype=float) for column in zip(*pairs))
    difference = clean - noisy
    p_value = float(wilcoxon(clean, noisy).pvalue) if np.any(difference != 0) else 1.0
    summary = {"benchmark": "mislabel-cost", "strategy": args.strategy, "turns": args.turns, "budget": args.budget,
               "rate": args.study_rate, "seeds": len(pairs), "oracle_accuracy": round(float(clean.mean()), 4),
               "noisy_accuracy": round(float(noisy.mean()), 4), "cost": round(float(difference.mean()), 4),
               "cost_standard_error": round(float(difference.std(ddof=1) / np.sqrt(len(pairs))), 4)
               if len(pairs) > 1 else None, "wilcoxon_p": round(p_value, 4),
               "mean_wrong_answers": round(float(wrong.mean()), 2)}
    print(f"mean accuracy {summary['oracle_accuracy']:.3f} (oracle) vs {summary['noisy_accuracy']:.3f} "
          f"({args.study_rate:.0%} mislabels): cost {summary['cost']:.3f} +- {summary['cost_standard_error']} "
          f"(Wilcoxon p = {summary['wilcoxon_p']})")
    return summary


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--strategy", default="active")
    parser.add_argument("--task", default="pack-lunchbox")
    parser.add_argument("--kitchen", default="kitchen-1")
    parser.add_argument("--turns", type=int, default=60)
    parser.add_argument("--budget", type=float, default=60.0)
    parser.add_argument("--change-every", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=1, help="episodes (seeds seed, seed+1, ...)")
    parser.add_argument("--mislabel-rate", type=float, default=0.0)
    parser.add_argument("--pictures", action="store_true", help="also write a numbered picture per question")
    parser.add_argument("--noise-study", type=int, default=0, metavar="SEEDS",
                        help="instead: paired episodes with and without mislabels over SEEDS seeds")
    parser.add_argument("--study-rate", type=float, default=0.1, help="mislabel rate of the noise study")
    parser.add_argument("--json", action="store_true", help="print a JSON summary as the last line")
    args = parser.parse_args(argv)
    summary = noise_study(args) if args.noise_study else benchmark(args)
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
