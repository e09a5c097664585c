"""Turns per CPU-second of a fixed sweep on this working tree and on an earlier commit, in one run (issue 43).

Both sides play the same frozen list of episodes (scripts/bench_sweep_episodes.toml: a844680's ch6-static
"static" condition and its first four ch7 conditions, every strategy, data set 0, seed 0) with the real
episode runner (``dialog.experiments.episodes.run_episode``: dialog manager, scripted teacher, pools, one
BLAS thread). Each side runs in its own subprocess with its own code first on PYTHONPATH: this working tree,
and the earlier commit unpacked by ``git archive`` into a temporary folder. Each side builds the episodes with
its own classes from the same plain data, every field its code has given explicitly; a field its code lacks
is left out only when the episode leaves it at this tree's default, else refused, so both sides always play
the same episodes. The sides alternate round by
round, so that the load of a shared machine falls on both alike. The time is the CPU time of every
``run_episode`` call, after a warm-up episode and with the pools loaded beforehand; the figure is turns
played per CPU-second, and the ratio is this tree's over the earlier commit's.

    python scripts/bench_sweep.py --json                      # against a844680; last line: one JSON object
    python scripts/bench_sweep.py --against HEAD~3 --rounds 3
    python scripts/bench_sweep.py --quick --json              # two short episodes (for a test)
    python scripts/bench_sweep.py --quick --episodes 1        # one (prepare-lunch: the cheaper data sets to render)
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from dataclasses import MISSING, asdict, fields, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EPISODES_FILE = Path(__file__).resolve().with_name("bench_sweep_episodes.toml")
DEFAULT_AGAINST = "a844680"
QUICK_EPISODES = ("ch7-time-constrained/dt-task/d0", "ch6-static-static/dt-task/d0")  # --episodes 1: the smaller
QUICK_TURNS = 10

# Runs in the subprocess, against whichever code is first on its PYTHONPATH (argv[1] is that folder).
DRIVER = r"""
import json, sys, tempfile, time
from pathlib import Path
import dialog
root = Path(sys.argv[1]).resolve()
if root not in Path(dialog.__file__).resolve().parents:
    sys.exit(f"the code imported is {dialog.__file__}, not the code under {root}")
from dataclasses import fields
from dialog.experiments.episodes import EpisodeSpec, run_episode
from dialog.experiments.pools import load_pools
from dialog.experiments.suite import Condition
def built(cls, row, what):
    # this code's own class from plain data, every field it has given; a field it lacks is left out only when the
    # episode leaves it at its default (the default of the code that wrote the list), else refused: it would be
    # another episode
    known = {f.name for f in fields(cls)}
    differing = sorted(k for k in set(row) - known if k not in defaults[cls.__name__]
                       or row[k] != defaults[cls.__name__][k])
    if differing:
        sys.exit(f"{what} sets {', '.join(f'{k}={row[k]!r}' for k in differing)}, which this code's "
                 f"{cls.__name__} does not have, so it cannot play the same episode")
    values = {k: v for k, v in row.items() if k in known}
    values.update({k: tuple(tuple(pair) for pair in values[k]) for k in ("costs", "teacher", "plan") if k in values})
    return cls(**values)
sent = json.load(sys.stdin)
rows, defaults = sent["rows"], sent["defaults"]
with tempfile.TemporaryDirectory(prefix="bench-sweep-") as folder:
    specs = []
    for index, row in enumerate(rows):
        what = f"episode {index + 1} ({row['suite']}/{row['strategy']})"
        row.update(condition=built(Condition, row["condition"], what), transcript=str(Path(folder) / f"{index}.jsonl"))
        specs.append(built(EpisodeSpec, row, what))
    for key in dict.fromkeys((s.task, s.kitchen, s.dataset + 1) for s in specs):
        load_pools(*key)
    run_episode(specs[0])  # warm-up: lazy imports and first calls are not the sweep's
    played = []
    for spec in specs:
        started = time.process_time()
        result = run_episode(spec)
        played.append({"turns": len(result["series"]["turn"]), "cpu_seconds": time.process_time() - started})
print(json.dumps(played))
"""


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default=DEFAULT_AGAINST, help=f"the earlier commit (default {DEFAULT_AGAINST})")
    parser.add_argument("--rounds", type=int, help="alternating rounds of both sides (default 2, 1 with --quick)")
    parser.add_argument("--quick", action="store_true",
                        help=f"only {len(QUICK_EPISODES)} episodes of {QUICK_TURNS} turns, one round unless --rounds")
    parser.add_argument("--episodes", type=int, metavar="N",
                        help="only the first N episodes of the list (of the --quick list with --quick)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if args.rounds is None:
        args.rounds = 1 if args.quick else 2
    if args.rounds < 1:
        parser.error(f"--rounds must be a whole number of at least 1, got {args.rounds}")
    if args.episodes is not None and args.episodes < 1:
        parser.error(f"--episodes must be a whole number of at least 1, got {args.episodes}")
    return args


def git(*arguments: str, binary: bool = False):
    return subprocess.run(["git", "-C", str(ROOT), *arguments], capture_output=True, text=not binary, check=False)


def resolve(commit: str) -> str:
    """The full hash of ``commit``; SystemExit with one line if this repository has no such commit."""
    found = git("rev-parse", "--verify", "--quiet", f"{commit}^{{commit}}") if not commit.startswith("-") else None
    if found is None or found.returncode != 0:
        raise SystemExit(f"bench_sweep: unknown commit {commit!r}: git cannot find it in {ROOT}; give a commit of "
                         "this repository (a hash, tag or branch name)")
    return found.stdout.strip()


def this_tree() -> str:
    """This working tree's commit, marked when it has uncommitted changes."""
    head = git("rev-parse", "--short", "HEAD").stdout.strip()
    dirty = git("status", "--porcelain", "--untracked-files=no").stdout.strip()
    return f"{head}+changes" if dirty else head


def unpack(commit: str, folder: Path) -> None:
    archive = git("archive", "--format=tar", commit, binary=True)
    if archive.returncode != 0:
        raise SystemExit(f"bench_sweep: git archive {commit} failed: {archive.stderr.decode().strip()}")
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
        tar.extractall(folder, filter="data")


def episode_rows(quick: bool, count: int | None = None) -> list[dict]:
    """The frozen episodes as plain data for the driver, which builds them with its own code's classes (its
    transcript paths are its own)."""
    sys.path.insert(0, str(ROOT))
    from dialog.experiments.fingerprint import fingerprint_episodes

    episodes = fingerprint_episodes(EPISODES_FILE)
    if quick:
        episodes = [e for label in QUICK_EPISODES for e in episodes if e.label == label]
        episodes = [replace(e, spec=replace(e.spec, condition=replace(e.spec.condition, turns=QUICK_TURNS)))
                    for e in episodes]
    return [{**_plain(e.spec), "condition": _plain(e.spec.condition)} for e in episodes[:count]]


def _plain(instance) -> dict:
    return {name: value for name, value in asdict(instance).items() if name != "transcript"}


def field_defaults() -> dict:
    """This tree's defaults of the episode classes' fields: an earlier commit's classes may lack later fields
    (issue 51: ``Condition.until_budget_spent``); its driver leaves such a field out only when an episode
    leaves it at this default, and refuses the episode otherwise, so both sides play the same episodes."""
    sys.path.insert(0, str(ROOT))
    from dialog.experiments.episodes import EpisodeSpec
    from dialog.experiments.suite import Condition

    return {cls.__name__: {f.name: f.default for f in fields(cls) if f.default is not MISSING}
            for cls in (EpisodeSpec, Condition)}


def play(code: Path, rows: list[dict], side: str) -> list[dict]:
    """Run the episodes with the code under ``code`` in a subprocess; each episode's turns and CPU seconds."""
    env = {**os.environ, "PYTHONPATH": str(code)}
    sent = {"rows": rows, "defaults": field_defaults()}
    done = subprocess.run([sys.executable, "-c", DRIVER, str(code)], input=json.dumps(sent), capture_output=True,
                          text=True, env=env, cwd=code, check=False)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise SystemExit(f"bench_sweep: the episodes did not run on {side}: {last}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def summary(label: str, rounds: list[list[dict]]) -> dict:
    turns = sum(e["turns"] for r in rounds for e in r)
    cpu = sum(e["cpu_seconds"] for r in rounds for e in r)
    per_round = [round(sum(e["turns"] for e in r) / sum(e["cpu_seconds"] for e in r), 1) for r in rounds]
    return {"commit": label, "turns": turns, "cpu_seconds": round(cpu, 3),
            "turns_per_cpu_second": round(turns / cpu, 1), "per_round": per_round}


def main(args) -> int:
    against = resolve(args.against)
    rows = episode_rows(args.quick, args.episodes)
    rounds = {"this": [], "against": []}
    with tempfile.TemporaryDirectory(prefix="bench-sweep-code-") as folder:
        old = Path(folder)
        unpack(against, old)
        for number in range(args.rounds):
            for side, code in (("this", ROOT), ("against", old)) if number % 2 == 0 else (("against", old),
                                                                                         ("this", ROOT)):
                rounds[side].append(play(code, rows, f"{'this tree' if side == 'this' else against[:7]}"))
                if not args.json:
                    print(f"round {number + 1}, {side}: {summary(side, rounds[side][-1:])['turns_per_cpu_second']} "
                          "turns per CPU-second", flush=True)
    report = {"episodes": len(rows), "rounds": args.rounds, "quick": args.quick,
              "this": summary(this_tree(), rounds["this"]), "against": summary(against[:7], rounds["against"])}
    report["ratio"] = round(report["this"]["turns_per_cpu_second"] / report["against"]["turns_per_cpu_second"], 2)
    if args.json:
        print(json.dumps(report))
    else:
        for side in ("this", "against"):
            row = report[side]
            print(f"{row['commit']:>16}: {row['turns']} turns in {row['cpu_seconds']:.1f} CPU-s, "
                  f"{row['turns_per_cpu_second']} turns per CPU-second (rounds: {row['per_round']})")
        print(f"ratio: {report['ratio']}x")
    return 0


if __name__ == "__main__":
    sys.exit(main(_parse(sys.argv[1:])))
