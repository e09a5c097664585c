"""The README's demo and study tables, made by running the commands they describe (issue 51 item 2).

``docs/readme-tables.toml`` says what runs: the demo's options, strategies and seeds, and a study file with the
participants a scripted teacher plays. :func:`run_readme` plays them one command after another (``teachbot demo
--json``, ``teachbot study run --simulated``, ``teachbot study report``) into ``results/experiments/readme/`` and
writes ``readme.json`` there; :func:`readme_tables` makes the ``summary:demo`` and ``summary:study`` blocks from
those files only. The run also hashes the transcripts of a cheap subset (one seed per strategy, one participant),
plays that subset a second time to see the same bytes, and keeps the hashes in ``readme.json``;
``scripts/experiments.py`` copies them into ``docs/readme-tables-record.json``, which
``tests/dialog/test_readme_tables.py`` replays.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from dialog.experiments.doc_tables import stamp
from dialog.experiments.fingerprint import ROOT, digest, located_nowhere
from dialog.printed_command import NAME as PROGRAM  # the README's commands name the installed program
from learning.datafiles import check_keys, integer, read_toml, section, tables, text, texts
from learning.errors import DataFileError, SettingsError

SPEC_FILE = ROOT / "docs" / "readme-tables.toml"
RECORD_FILE = ROOT / "docs" / "readme-tables-record.json"
NAME = "readme"  # what --suites calls this run
REGENERATE = "make readme-tables"  # what a stale record tells the reader to run


@dataclass(frozen=True)
class ReadmeSpec:
    """``docs/readme-tables.toml``: the demo's rows and the simulated study."""

    demo_options: tuple[str, ...]
    strategies: tuple[tuple[str, str], ...]  # (name for --strategy, the row's words)
    seeds: tuple[int, ...]
    checked_seed: int
    study: str  # the study file, relative to the checkout
    participants: tuple[str, ...]
    checked_participant: str
    figure: str  # where the report's learning-curve plot is copied, relative to the checkout
    caption: str


def load_spec(path: Path = SPEC_FILE) -> ReadmeSpec:
    """Read and check the file; a DataFileError naming it and what is wrong."""
    table = read_toml(path, "README tables")
    check_keys(table, str(path), required=("demo", "study"))
    demo, study = section(table, "demo", str(path)), section(table, "study", str(path))
    where = f"{path} [demo]"
    check_keys(demo, where, required=("options", "seeds", "checked_seed", "strategy"))
    seeds = demo["seeds"]
    if not isinstance(seeds, list) or not seeds or not all(isinstance(s, int) and s >= 0 for s in seeds):
        raise DataFileError(f"{where}: 'seeds' must be a non-empty list of whole numbers >= 0, got {seeds!r}")
    checked_seed = integer(demo, "checked_seed", where, low=0)
    if checked_seed not in seeds:
        raise DataFileError(f"{where}: 'checked_seed' {checked_seed} is not one of the seeds {seeds}")
    strategies = []
    for index, row in enumerate(tables(demo, "strategy", where, nonempty=True), 1):
        label = f"{where} strategy {index}"
        check_keys(row, label, required=("name", "row"))
        strategies.append((text(row, "name", label), text(row, "row", label)))
    options = texts(demo, "options", where)
    taken = {"--strategy", "--seed", "--transcript", "--json"} & set(options)
    if taken:
        raise DataFileError(f"{where}: 'options' must not give {', '.join(sorted(taken))}: the run sets them")
    where = f"{path} [study]"
    check_keys(study, where, required=("file", "participants", "checked_participant", "figure", "caption"))
    participants = texts(study, "participants", where, nonempty=True)
    checked = text(study, "checked_participant", where, choices=participants)
    study_file = text(study, "file", where)
    if not (ROOT / study_file).is_file():
        raise DataFileError(f"{where}: 'file' {study_file} is not a file of the checkout")
    return ReadmeSpec(options, tuple(strategies), tuple(seeds), checked_seed, study_file, participants, checked,
                      text(study, "figure", where), text(study, "caption", where))


def demo_command(spec: ReadmeSpec, strategy: str, seed: int, transcript: Path) -> list[str]:
    return [PROGRAM, "demo", *spec.demo_options, "--strategy", strategy, "--seed", str(seed),
            "--transcript", str(transcript), "--json"]


def study_commands(spec: ReadmeSpec, participants, folder: Path) -> list[list[str]]:
    """One ``study run --simulated`` per participant; the report is :func:`report_command`."""
    return [[PROGRAM, "study", "run", spec.study, "--participant", p, "--simulated", "--no-viewer",
             "--folder", str(folder)] for p in participants]


def report_command(spec: ReadmeSpec, folder: Path) -> list[str]:
    return [PROGRAM, "study", "report", spec.study, "--simulated", "--folder", str(folder)]


def run_cli(words: list[str]) -> str:
    """One ``teachbot`` command in a process of its own, in the checkout; its standard output."""
    done = subprocess.run([sys.executable, "-m", "dialog.cli", *words[1:]], cwd=ROOT, capture_output=True,
                          text=True, stdin=subprocess.DEVNULL)
    if done.returncode != 0:
        raise SystemExit(f"experiments: '{shlex.join(words)}' failed with exit code {done.returncode}:\n"
                         f"{done.stderr[-2000:]}")
    return done.stdout


def normalised(data: bytes, folder: Path) -> bytes:
    """A transcript as hashed: the run's own folder written as ``<out>`` and the checkout's as ``<repo>``."""
    return located_nowhere(data.replace(str(folder.resolve()).encode(), b"<out>"))


def checked_runs(spec: ReadmeSpec, out: Path) -> dict[str, str]:
    """Play the cheap subset into ``out`` (one seed per strategy, one participant): {label: SHA-256}."""
    for strategy, _ in spec.strategies:
        run_cli(demo_command(spec, strategy, spec.checked_seed, demo_transcript(out, strategy, spec.checked_seed)))
    for words in study_commands(spec, [spec.checked_participant], out / "study"):
        run_cli(words)
    return checked_hashes(spec, out)


def demo_transcript(out: Path, strategy: str, seed: int) -> Path:
    """Where a demo episode's transcript goes (its folder is made: the demo makes none outside the checkout)."""
    (out / "demo").mkdir(parents=True, exist_ok=True)
    return out / "demo" / f"{strategy}-seed{seed}.jsonl"


def checked_hashes(spec: ReadmeSpec, out: Path) -> dict[str, str]:
    """The SHA-256 of the subset's files under ``out`` (demo transcripts; the participant's every record)."""
    hashes = {f"demo/{strategy}/seed{spec.checked_seed}":
              digest(normalised(demo_transcript(out, strategy, spec.checked_seed).read_bytes(), out))
              for strategy, _ in spec.strategies}
    for path in sorted((out / "study" / spec.checked_participant).glob("*.jsonl")):
        hashes[f"study/{spec.checked_participant}/{path.name}"] = digest(normalised(path.read_bytes(), out))
    return hashes


def run_readme(spec: ReadmeSpec, out: Path, meta: dict, say: Callable[[str], None] = print) -> dict:
    """Play every command of ``spec`` into ``out`` (emptied first), one after another; write and return
    ``out/readme.json``: ``meta`` (commit, dirty, date, cores, command) with the rows and the checked hashes."""
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    shown = os.path.relpath(out, ROOT) if out.resolve().is_relative_to(ROOT) else str(out)
    rows = []
    for strategy, _ in spec.strategies:
        for seed in spec.seeds:
            words = demo_command(spec, strategy, seed, demo_transcript(out, strategy, seed))
            summary = json.loads(run_cli(words).strip().splitlines()[-1])
            rows.append({"strategy": strategy, "seed": seed, "accuracy": summary["accuracy"]})
            say(f"  demo {strategy} seed {seed}: {summary['accuracy']:.3f}")
    for words in study_commands(spec, spec.participants, out / "study"):
        run_cli(words)
        say(f"  study {words[words.index('--participant') + 1]}: done")
    run_cli(report_command(spec, out / "study"))
    hashes = checked_hashes(spec, out)
    again = checked_runs(spec, out / "replay")
    if again != hashes:
        moved = sorted(label for label in hashes if again.get(label) != hashes[label])
        raise SystemExit(f"experiments: the same seeds gave other bytes on a second run ({', '.join(moved)}): "
                         "the README tables cannot be checked by their transcripts' hashes")
    shutil.rmtree(out / "replay")
    readme = {**meta, "demo": rows, "study_command": study_loop(spec, Path(shown) / "study"), "checked": hashes}
    (out / "readme.json").write_text(json.dumps(readme, indent=1) + "\n")
    return readme


def study_loop(spec: ReadmeSpec, folder: Path) -> str:
    """The shell line a reader can type to make the study's records and report as the run did."""
    run = shlex.join(study_commands(spec, ["PARTICIPANT"], folder)[0]).replace("PARTICIPANT", "$p")
    return f"for p in {' '.join(spec.participants)}; do {run}; done; {shlex.join(report_command(spec, folder))}"


def write_check(readme: dict, path: Path = RECORD_FILE) -> None:
    """The record the test replays: which run made the tables and its checked transcripts' hashes."""
    path.write_text(json.dumps({"commit": readme["commit"], "date": readme["date"], "command": readme["command"],
                                "checked": readme["checked"]}, indent=1) + "\n")


def readme_tables(spec: ReadmeSpec, readme: dict, out: Path) -> dict[str, str]:
    """The ``summary:demo`` and ``summary:study`` blocks from the run's files (the study figure copied too)."""
    line = stamp(readme, readme["command"])
    figure = out / "study" / "report" / f"study-{read_toml(ROOT / spec.study, 'study')['name']}-curves.png"
    if figure.exists():
        (ROOT / spec.figure).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(figure, ROOT / spec.figure)
    report = (out / "study" / "report" / "report.md").read_text(encoding="utf-8")
    study = [f"Records and report of `{readme['study_command']}`:", "",
             *table_columns(report, "condition", ("condition", "n", "final accuracy (mean)", "sd",
                                                  "questions per session label/demo/feature/none")), "",
             *table_columns(report, "measure", ("measure", "conditions", "n", "median difference", "W", "p",
                                                "effect r"), ("final accuracy",)), "",
             f"![{spec.caption}]({spec.figure})", "", line]
    return {"summary:demo": demo_table(spec, readme) + "\n\n" + line, "summary:study": "\n".join(study)}


def demo_table(spec: ReadmeSpec, readme: dict) -> str:
    seeds = sorted({row["seed"] for row in readme["demo"]})
    lines = [f"Measured with the options `{' '.join(spec.demo_options)}`, each strategy with `--strategy NAME "
             f"--seed S --json` for S = {', '.join(map(str, seeds))} (accuracy on six held-out scenes; chance 0.25; "
             "the demo's speed is measured by scripts/bench_episode.py):", "",
             "| strategy | accuracy per seed | mean |", "|---|---|---:|"]
    for strategy, words in spec.strategies:
        rows = [row for row in readme["demo"] if row["strategy"] == strategy]
        accuracies = [row["accuracy"] for row in sorted(rows, key=lambda row: row["seed"])]
        lines.append(f"| {words} | {' '.join(f'{a:.3f}' for a in accuracies)} | "
                     f"{sum(accuracies) / len(accuracies):.3f} |")
    return "\n".join(lines)


def table_columns(report: str, first: str, columns: tuple[str, ...], keep: tuple[str, ...] = ()) -> list[str]:
    """The Markdown table of ``report`` whose header begins with ``first``, cut to ``columns`` (and to the rows
    whose first cell is in ``keep``, when given)."""
    lines = report.splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith(f"| {first} |")), None)
    if start is None:
        raise SettingsError(f"the study report has no table beginning '| {first} |'")
    end = next((i for i in range(start, len(lines)) if not lines[i].startswith("|")), len(lines))
    cells = [[c.strip() for c in line.strip().strip("|").split("|")] for line in lines[start:end]]
    header = cells[0]
    missing = [c for c in columns if c not in header]
    if missing:
        raise SettingsError(f"the study report's '{first}' table has no column {missing[0]!r}")
    picked = [header.index(c) for c in columns]
    body = [row for row in cells[2:] if not keep or row[0] in keep]
    return ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns),
            *("| " + " | ".join(row[i] for i in picked) + " |" for row in body)]
