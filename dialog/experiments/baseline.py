"""Stored baselines: mean accuracy at checkpoints with tolerance bands; ``--check`` compares against them."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from dialog.experiments.analysis import CheckpointSummary
from dialog.experiments.suite import SUITE_DIR, Suite, SuiteError
from dialog.output_paths import keep_superseded
from learning.datafiles import inside
from learning.errors import SettingsError
from learning.strategies import is_external

BASELINE_DIR = SUITE_DIR / "baselines"
DEFAULT_TOLERANCE = 0.05


def baseline_path(suite: Suite) -> Path:
    """``dialog/suites/baselines/<name>.json``; the suite's name is a file name (no separators), and a link that
    leads out of the baselines folder is refused."""
    return inside(BASELINE_DIR, BASELINE_DIR / f"{suite.name}.json", "baseline")


def make_baseline(suite: Suite, summaries: list[CheckpointSummary], tolerance: float = DEFAULT_TOLERANCE) -> dict:
    """Band = mean ± max(tolerance, 3 standard errors) at every checkpoint."""
    bands: dict = {}
    for s in summaries:
        entry = bands.setdefault(s.condition, {}).setdefault(s.strategy, {})
        for checkpoint, mean, error in zip(s.checkpoints, s.mean, s.error):
            half = max(tolerance, 3.0 * float(error))
            entry[str(checkpoint)] = {"mean": round(float(mean), 4),
                                      "band": [round(float(mean) - half, 4), round(float(mean) + half, 4)]}
    return {"suite": suite.name, "axis": suite.axis, "seeds": list(suite.seeds), "datasets": suite.datasets,
            "data_seed": suite.data_seed, "bands": bands}


def write_baseline(suite: Suite, summaries: list[CheckpointSummary], path: Path | None = None) -> Path:
    """Store the baseline; one already there is first kept as ``<name>.json.superseded-N`` (said on stderr)."""
    path = path or baseline_path(suite)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(make_baseline(suite, summaries), indent=1) + "\n"
    if path.is_file() and path.read_text(encoding="utf-8", errors="replace") != text:
        kept = keep_superseded(path, "baseline")
        print(f"the earlier baseline is kept as {kept}", file=sys.stderr, flush=True)
    path.write_text(text, encoding="utf-8")
    return path


def read_baseline(path: Path) -> dict:
    """A stored baseline, every field checked: ``{"bands": {condition: {strategy: {checkpoint: {"mean": m,
    "band": [low, high]}}}}, "data_seed": n, ...}``; a damaged one is a SuiteError ``FILE: what (expected ...)``."""
    def refuse(what: str, expected: str) -> SuiteError:
        return SuiteError(f"{path}: {what} (expected {expected}); restore it from git or rewrite it with "
                          "--update-baseline")

    try:
        stored = json.loads(path.read_bytes().decode("utf-8"))
    except OSError as error:
        raise SuiteError(f"{path}: cannot read the baseline ({error.strerror or error})") from None
    except UnicodeDecodeError as error:
        raise refuse(f"not UTF-8 text (byte {error.start})", "the JSON teachbot writes") from None
    except (json.JSONDecodeError, RecursionError) as error:
        raise refuse(f"not JSON ({getattr(error, 'msg', 'nested too deeply')})", "the JSON teachbot writes") from None
    if not isinstance(stored, dict) or not isinstance(stored.get("bands"), dict):
        raise refuse("no 'bands' table", "an object with 'bands': {condition: {strategy: {checkpoint: ...}}}")
    seed = stored.get("data_seed", 0)
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise refuse(f"'data_seed' is {json.dumps(seed)[:40]}", "a whole number of 0 or more")
    for condition, strategies in stored["bands"].items():
        for strategy, checkpoints in (strategies.items() if isinstance(strategies, dict) else [(None, None)]):
            for checkpoint, entry in (checkpoints.items() if isinstance(checkpoints, dict) else [(None, None)]):
                where = f"bands.{condition}.{strategy}.{checkpoint}"
                band = entry.get("band") if isinstance(entry, dict) else None
                mean = entry.get("mean") if isinstance(entry, dict) else None
                numbers = [mean, *band] if isinstance(band, list) and len(band) == 2 else []
                if checkpoint is None or not str(checkpoint).isdigit() or not numbers or not all(
                        isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in numbers) \
                        or band[0] > band[1]:
                    raise refuse(f"{where} is {json.dumps(entry)[:60]}",
                                 "{checkpoint: {\"mean\": m, \"band\": [low, high]}} with finite numbers, low <= high")
    return stored


def refuse_other_data_seed(suite: Suite, path: Path | None = None) -> None:
    """``--check`` compares like with like: a baseline made on data from another seed is refused (SuiteError)."""
    path = path or baseline_path(suite)
    if not path.exists():
        return  # a missing baseline is reported by check_against_baseline
    stored = read_baseline(path).get("data_seed", 0)
    if stored != suite.data_seed:
        raise SuiteError(f"--check: the baseline {path} was made on the data sets of data seed {stored}, this run "
                         f"uses data seed {suite.data_seed}; check with --data-seed {stored}, or run without --check")


def refuse_baseline_from_another_run(suite: Suite, original: Suite) -> None:
    """``--update-baseline`` stores only the suite's own run: refuse (SettingsError, before anything runs) a run
    that adds --weights strategies or trained policies, uses data sets of another seed than the suite file's
    (``original``, as loaded), or changes its strategies, seeds, conditions or data sets on the command line."""
    if suite.weights:
        raise SettingsError(f"--update-baseline stores the suite's own run as the baseline of '{suite.name}'; this run "
                            f"adds --weights strategies ({', '.join(suite.weights)}): run it without "
                            "--update-baseline, or store the baseline without --weights")
    if suite.data_seed != original.data_seed:
        raise SettingsError(f"--update-baseline stores the suite's own run as the baseline of '{suite.name}', made on "
                            f"the data sets of data seed {original.data_seed}; this run uses data seed "
                            f"{suite.data_seed}: run it without --update-baseline, or store the baseline without "
                            "--data-seed")
    changed = [option for option, field in (("--strategies", "strategies"), ("--seeds", "seeds"),
                                            ("--budget or --embodied-costs", "conditions"), ("--datasets", "datasets"))
               if getattr(suite, field) != getattr(original, field)]
    if changed:
        raise SettingsError(f"--update-baseline stores the suite's own run as the baseline of '{suite.name}'; this run "
                            f"changes the suite with {', '.join(changed)}: run it without --update-baseline, or "
                            "store the baseline without those options (or edit the suite file)")


class BaselineFailures(list):
    """The readable failures of a baseline check (a list of str; empty: all inside) and ``checked``, how many
    checkpoint bands were compared, for the pass line ("12 of 12 within bands")."""

    checked: int = 0

    def verdict(self) -> str:
        within = max(self.checked - sum(" band [" in failure for failure in self), 0)
        if not self:
            return f"baseline check: passed ({within} of {self.checked} within bands)"
        return f"baseline check: FAILED ({len(self)} problem{'s' if len(self) != 1 else ''}; {within} of " \
               f"{self.checked} bands within)"


def check_against_baseline(suite: Suite, summaries: list[CheckpointSummary],
                           path: Path | None = None) -> BaselineFailures:
    """Readable differences for every checkpoint mean outside its stored band (empty: all inside)."""
    failures = BaselineFailures()
    path = path or baseline_path(suite)
    if not path.exists():
        failures.append(f"no stored baseline for suite '{suite.name}' at {path}; run with --update-baseline first")
        return failures
    stored = read_baseline(path)
    bands, data_seed = stored["bands"], stored.get("data_seed", 0)
    if data_seed != suite.data_seed:
        failures.append(f"baseline {path} was made on data seed {data_seed}, this run on data seed "
                        f"{suite.data_seed}: not comparable")
        return failures
    axis = suite.axis  # questions, turns or demonstrations
    for s in summaries:
        stored = bands.get(s.condition, {}).get(s.strategy)
        if stored is None and (s.strategy in suite.weights or is_external(s.strategy)):
            continue  # a --weights strategy, a trained policy or a user's class: no baseline to hold it to
        if stored is None:
            failures.append(f"{s.strategy}/{s.condition}: not in the baseline")
            continue
        for checkpoint, mean in zip(s.checkpoints, s.mean):
            entry = stored.get(str(checkpoint))
            if entry is None or not np.isfinite(mean):
                continue
            low, high = entry["band"]
            failures.checked += 1
            if not low <= mean <= high:
                side = "below" if mean < low else "above"
                failures.append(f"{s.strategy}/{s.condition} after {checkpoint} {axis}: accuracy {mean:.3f} is "
                                f"{side} its band [{low:.3f}, {high:.3f}] (baseline {entry['mean']:.3f})")
    return failures
