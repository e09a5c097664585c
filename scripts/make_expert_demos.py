"""Make the shipped expert demonstrations (learning/irl/expert-demos/) with the scripted expert.

The thesis's training condition (§7.4.1): prepare-lunch, budget 15, 30 turns, a scene change every 10 turns,
costs DQ 2, FSQ 2, LQ 1, NQ 0; one episode per seed (default seeds 1-5: `teachbot learn-weights` trains on
three and validates on the rest). Reproducible: every random choice comes from the episode seed. The
transcripts go to --transcripts (not shipped).

    .venv/bin/python scripts/make_expert_demos.py [--seeds 1 2 3 4 5] [--out DIR] [--transcripts DIR] [--json]
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

from dialog.expert import ExpertSettings, run_expert_episode  # noqa: E402
from dialog.scripted_expert import ScriptedExpertChooser  # noqa: E402
from learning.irl.learn import SHIPPED_DEMOS  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    parser.add_argument("--out", type=Path, default=SHIPPED_DEMOS)
    parser.add_argument("--transcripts", type=Path, default=None, help="keep the transcripts here (default: dropped)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix="expert-demos-"))
    summary = []
    try:
        for seed in args.seeds:
            started = time.perf_counter()
            outcome = run_expert_episode(ExpertSettings(seed=seed), ScriptedExpertChooser(), scratch,
                                         say=lambda text: None)
            target = args.out / outcome.demonstration.name
            shutil.copyfile(outcome.demonstration, target)
            if args.transcripts is not None:
                args.transcripts.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(outcome.transcript, args.transcripts / outcome.transcript.name)
            row = {"seed": seed, "file": str(target.relative_to(ROOT) if target.is_relative_to(ROOT) else target),
                   "accuracy": round(outcome.result.accuracy, 4), "budget_spent": outcome.result.budget_spent,
                   "queries": outcome.result.queries, "seconds": round(time.perf_counter() - started, 2)}
            summary.append(row)
            print(f"seed {seed}: {row['queries']}, spent {row['budget_spent']:g}, accuracy {row['accuracy']:.3f}, "
                  f"{row['seconds']:.1f} s -> {row['file']}")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    if args.json:
        print(json.dumps({"episodes": summary}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
