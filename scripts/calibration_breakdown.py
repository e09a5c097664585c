"""Per condition and grid value, what the calibration run's episodes did (docs/calibration.md).

Reads the transcripts ``scripts/calibrate_dt.py`` left under its results folder (default
results/calibration) and prints, for each preset, condition and grid value: episodes, mean turns used, mean
questions asked, mean final accuracy, how many reached the turn bound, and the share of the spent budget
that went on demonstrations. It decides nothing: the rule's choice is calibrate_dt.py's.

    .venv/bin/python scripts/calibration_breakdown.py [--results DIR] [--json]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

NAME = re.compile(r"^(?P<preset>.+)-grid(?P<index>\d+)-d\d+-s\d+\.jsonl$")


def episode_summary(path: Path) -> tuple[int, int, float, bool, float]:
    """(turns, questions, final accuracy, reached the bound, demonstration share of the spent budget)."""
    lines = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    session, turns = lines[0]["session"], [line for line in lines[1:] if "turn" in line]
    spent = sum(t.get("cost", 0.0) for t in turns)
    demos = sum(t.get("cost", 0.0) for t in turns if t["action"]["kind"] == "demo")
    questions = sum(t["action"]["kind"] != "none" for t in turns)
    return len(turns), questions, float(turns[-1]["accuracy"]), len(turns) >= session["turns"], demos / max(spent, 1e-9)


def breakdown(results: Path) -> list[dict]:
    groups: dict[tuple[str, str, int], list] = defaultdict(list)
    for path in sorted(results.glob("*/data-seed-*/transcripts/*/*.jsonl")):
        match = NAME.match(path.name)
        if match:
            groups[(match["preset"], path.parent.name, int(match["index"]))].append(episode_summary(path))
    rows = []
    for (preset, condition, index), episodes in sorted(groups.items()):
        values = np.array(episodes, dtype=float)
        rows.append({"preset": preset, "condition": condition, "grid_index": index, "episodes": len(episodes),
                     "turns": round(values[:, 0].mean(), 1), "questions": round(values[:, 1].mean(), 1),
                     "final_accuracy": round(values[:, 2].mean(), 3), "at_bound": int(values[:, 3].sum()),
                     "demo_share": round(values[:, 4].mean(), 2)})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", type=Path, default=Path("results/calibration"))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = breakdown(args.results)
    if not rows:
        print(f"error: no calibration transcripts under {args.results} (run scripts/calibrate_dt.py first)",
              file=sys.stderr)
        return 2
    print("| preset | condition | grid value # | episodes | turns | questions | final accuracy | at the bound | "
          "demo share |\n|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['preset']} | {r['condition']} | {r['grid_index']} | {r['episodes']} | {r['turns']} | "
              f"{r['questions']} | {r['final_accuracy']:.3f} | {r['at_bound']} | {r['demo_share']:.0%} |")
    if args.json:
        print(json.dumps(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
