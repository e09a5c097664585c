"""Does the record in the docs still describe the code? (issue 39 item 7)

``make experiments`` writes ``docs/experiments-record.json`` beside the tables it rewrites: the commit, and the
fingerprint's transcript hashes (``dialog/data/fingerprint-transcripts.json``, one short fixed episode per
strategy and suite condition) as they were for that run. The fingerprint's own test keeps that file equal to
what the code decides, so comparing the two says which strategies' decisions have moved since the record was
made. A refactor or speed-up keeps every hash and the record stays current; a change that moves a decision
makes the record stale for the strategies it moved.

The README and docs/experiments.md carry the verdict in words between ``<!-- record-status:begin -->`` and
``<!-- record-status:end -->``; ``tests/dialog/test_record.py`` fails when those words are not what
:func:`status_text` says now, so a decision-changing commit cannot land silently: rerun ``make experiments``,
or rewrite the caveat with ``python -m dialog.experiments.record --write``, which names what is stale.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from dialog.experiments.fingerprint import HASHES_FILE, ROOT, recorded

RECORD_FILE = ROOT / "docs" / "experiments-record.json"
STATUS_DOCS = ("README.md", "docs/experiments.md")
BEGIN, END = "<!-- record-status:begin -->", "<!-- record-status:end -->"
BLOCK = re.compile(re.escape(BEGIN) + r"\n(.*?)\n" + re.escape(END), re.S)


@dataclass(frozen=True)
class RecordStatus:
    """The record's commit and, per fingerprint episode it stored, whether the code still decides the same."""

    commit: str
    stored: int  # fingerprint episodes the record stored (0: it predates the fingerprint)
    moved: tuple[str, ...]  # labels group/strategy/dN whose transcript differs now (or is no longer run)

    @property
    def current(self) -> bool:
        return self.stored > 0 and not self.moved

    def stale_strategies(self) -> list[str]:
        return sorted({label.split("/", 1)[1].rsplit("/", 1)[0] for label in self.moved})  # group/STRATEGY/dN


def write_record(commit: str, date: str, hashes_file: Path = HASHES_FILE, path: Path = RECORD_FILE) -> None:
    """What ``make experiments`` leaves beside its tables: the commit and the fingerprint it was made with."""
    episodes = {label: hashes["transcript"] for label, hashes in sorted(recorded(hashes_file).items())}
    path.write_text(json.dumps({"commit": commit, "date": date, "fingerprint": episodes}, indent=1) + "\n")


def record_status(path: Path = RECORD_FILE, hashes_file: Path = HASHES_FILE) -> RecordStatus:
    """Compare the record's fingerprint with the one recorded for the code now."""
    record = json.loads(path.read_text(encoding="utf-8"))
    now = recorded(hashes_file)
    stored = record.get("fingerprint", {})
    moved = tuple(label for label, transcript in stored.items()
                  if label not in now or now[label]["transcript"] != transcript)
    return RecordStatus(record["commit"], len(stored), moved)


def status_text(status: RecordStatus) -> str:
    """The record's status in words, as the README and docs/experiments.md must say it."""
    made = f"The record (`make experiments` at commit {status.commit[:7]})"
    if status.current:
        return (f"{made} describes the code: the fingerprint of the decisions of every strategy it ran "
                f"({status.stored} short fixed episodes) is unchanged since.")
    if not status.stored:
        return (f"{made} predates the fingerprint of decisions, and decisions have changed since: **every table "
                "made by it is stale** until `make experiments` is rerun.")
    return (f"{made} is **stale for {', '.join(status.stale_strategies())}**: their decisions have changed since "
            f"({len(status.moved)} of {status.stored} fingerprint episodes moved); the other strategies' rows still "
            "describe the code, and the findings that compare with a stale strategy are stale too.")


def blocks(text: str) -> list[str]:
    return BLOCK.findall(text)


def rewrite(text: str, words: str) -> str:
    return BLOCK.sub(lambda _: f"{BEGIN}\n{words}\n{END}", text)


def write_status(words: str) -> list[str]:
    """Rewrite the status block of every doc in STATUS_DOCS with ``words``; the docs that have no block (and so
    were left alone) are returned."""
    missing = []
    for doc in STATUS_DOCS:
        path = ROOT / doc
        text = path.read_text(encoding="utf-8")
        if not blocks(text):
            missing.append(doc)
            continue
        path.write_text(rewrite(text, words), encoding="utf-8")
    return missing


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"rewrite the status in {' and '.join(STATUS_DOCS)}")
    args = parser.parse_args(argv)
    words = status_text(record_status())
    print(words)
    missing = write_status(words) if args.write else []
    for doc in missing:
        print(f"error: {doc} has no {BEGIN} ... {END} block to rewrite", file=sys.stderr)
    return 2 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
