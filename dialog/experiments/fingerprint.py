"""A fingerprint of what the code decides: the SHA-256 of the transcripts of short fixed episodes.

``dialog/data/fingerprint.toml`` lists the episodes (frozen copies of suite conditions, shortened, a few
strategies each); ``dialog/data/fingerprint-transcripts.json`` holds each transcript's hash as recorded. A
commit that changes any decision or number changes a hash; a speed-up that keeps every transcript
byte-identical changes none, so :func:`compare` tells the two apart (tests/dialog/test_fingerprint.py).
``python -m dialog.experiments.fingerprint`` compares (``--record`` writes the hashes anew; ``--json`` prints
them). Alongside the transcripts, the per-turn series the reports are built from are hashed too.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from dialog.experiments.episodes import EpisodeSpec, run_episode
from dialog.experiments.suite import Condition
from learning.datafiles import check_keys, integer, number, read_toml, section, tables, text, texts
from learning.errors import DataFileError

DATA_DIR = Path(__file__).resolve().parents[1] / "data"
ROOT = Path(__file__).resolve().parents[2]
EPISODES_FILE = DATA_DIR / "fingerprint.toml"
HASHES_FILE = DATA_DIR / "fingerprint-transcripts.json"
GROUP_FIELDS = ("name", "task", "kitchen", "strategies", "datasets", "costs", "budget", "turns", "change_every")
GROUP_OPTIONAL = ("objects_per_scene", "seconds")


@dataclass(frozen=True)
class FingerprintEpisode:
    """One fixed episode: its label (group/strategy/d<data set>) and the spec that runs it."""

    label: str
    spec: EpisodeSpec


def fingerprint_episodes(path: Path = EPISODES_FILE, transcripts: Path = Path(".")) -> list[FingerprintEpisode]:
    """The episodes of ``path`` in file order, their transcripts under ``transcripts``.

    The file holds ``[[group]]`` tables, each a frozen suite condition (name, task, kitchen, costs, budget,
    turns, change_every, optionally objects_per_scene and seconds) with its strategies and data sets (seed 0);
    scripts/bench_sweep.py reads its own list of episodes in the same form.
    """
    table = read_toml(path, "episode list")
    check_keys(table, str(path), required=("group",))
    episodes = []
    for index, group in enumerate(tables(table, "group", str(path), nonempty=True)):
        where = f"{path} [[group]] {index + 1}"
        check_keys(group, where, required=GROUP_FIELDS, optional=GROUP_OPTIONAL)
        name = text(group, "name", where)
        seconds = number(group, "seconds", where, None, above=0)
        objects = integer(group, "objects_per_scene", where, None, low=1)
        condition = Condition(name, number(group, "budget", where, low=0), integer(group, "turns", where, low=1),
                              integer(group, "change_every", where, low=1), None if seconds is None else seconds,
                              objects)
        costs = tuple(sorted((str(k), v) for k, v in section(group, "costs", where).items()))
        datasets = group["datasets"]
        if not isinstance(datasets, list) or not all(isinstance(d, int) and d >= 0 for d in datasets):
            raise DataFileError(f"{where}: 'datasets' must be a list of whole numbers >= 0, got {datasets!r}")
        for strategy in texts(group, "strategies", where, nonempty=True):
            for dataset in datasets:
                label = f"{name}/{strategy}/d{dataset}"
                file_name = "".join(c if c.isalnum() or c in "-_." else "-" for c in strategy)  # rl:a/b.toml too
                transcript = transcripts / name / f"{file_name}-d{dataset}.jsonl"
                spec = EpisodeSpec(suite=f"fingerprint-{name}", task=text(group, "task", where),
                                   kitchen=text(group, "kitchen", where), strategy=strategy, condition=condition,
                                   dataset=dataset, seed=0, costs=costs, teacher=(), transcript=str(transcript))
                episodes.append(FingerprintEpisode(label, spec))
    return episodes


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def located_nowhere(transcript: bytes) -> bytes:
    """A transcript with the checkout's own folder written as ``<repo>``: an RL policy's file is recorded by its
    absolute path, which says where the clone is, not what the code decided."""
    return transcript.replace(str(ROOT).encode(), b"<repo>")


def fingerprint(path: Path = EPISODES_FILE) -> dict[str, dict[str, str]]:
    """Run every fixed episode; {label: {"transcript": sha256 of its file, "series": sha256 of its series}}."""
    hashes = {}
    with tempfile.TemporaryDirectory(prefix="teachbot-fingerprint-") as folder:
        for episode in fingerprint_episodes(path, Path(folder)):
            result = run_episode(episode.spec)
            series = json.dumps({"series": result["series"], "accuracy": result["accuracy"]}, sort_keys=True)
            hashes[episode.label] = {"transcript": digest(located_nowhere(Path(episode.spec.transcript).read_bytes())),
                                     "series": digest(series.encode())}
    return hashes


def recorded(path: Path = HASHES_FILE) -> dict[str, dict[str, str]]:
    """The hashes as recorded (``--record``)."""
    try:
        return json.loads(path.read_text())["episodes"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise DataFileError(f"{path}: not a recorded fingerprint ({error}); write one with "
                            "python -m dialog.experiments.fingerprint --record") from None


def compare(now: dict, then: dict) -> list[str]:
    """One line per episode whose transcript or series differs from the recording (or is not in both)."""
    lines = [f"{label}: not recorded" for label in now if label not in then]
    lines += [f"{label}: recorded but no longer run" for label in then if label not in now]
    for label in (label for label in now if label in then):
        moved = [part for part in ("transcript", "series") if now[label][part] != then[label].get(part)]
        if moved:
            lines.append(f"{label}: {' and '.join(moved)} changed")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help=f"write the hashes to {HASHES_FILE.name}")
    parser.add_argument("--json", action="store_true", help="print the hashes as JSON")
    args = parser.parse_args(argv)
    now = fingerprint()
    if args.record:
        HASHES_FILE.write_text(json.dumps({"episodes": now}, indent=1, sort_keys=True) + "\n")
    if args.json:
        print(json.dumps(now, indent=1, sort_keys=True))
        return 0
    try:
        changed = compare(now, recorded())
    except DataFileError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print("\n".join(changed) if changed else f"all {len(now)} transcripts byte-identical to the recording")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
