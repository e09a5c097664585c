"""``make experiments``: rerun every suite the docs cite and rewrite every results table from that run.

    python scripts/experiments.py                  # run docs/experiments.toml, then rewrite the docs' tables
    python scripts/experiments.py --render         # rewrite the tables from the last run's files only
    python scripts/experiments.py --suites ch7 ... # only these runs (the others' tables are left alone)
    python scripts/experiments.py --suites readme  # only the README's demo and study tables (make readme-tables)

Each run is a ``teachbot regress`` command (episodes suites with ``--data-seeds``);
results go to ``results/experiments/SUITE/``, and ``results/experiments/manifest.json``
records the commit, the commands, the machine's cores and every wall time. Every
table is written between its markers with a stamp line naming that commit and
command (``dialog/experiments/doc_tables.py``). A run refuses a tree with
uncommitted changes to the code (``--allow-dirty`` runs anyway and the stamps say so).

The plan's ``readme`` file (``docs/readme-tables.toml``) lists the README's two other measured tables: the
demo's (options, strategies, seeds) and the simulated example study's (study file, participants). The run
named ``readme`` plays those ``teachbot demo`` and ``teachbot study`` commands one after another into
``results/experiments/readme/``, rewrites the blocks ``summary:demo`` and ``summary:study`` wherever the plan's
docs have their markers (and copies the study's curves figure), and writes the SHA-256 of a cheap subset's
transcripts to ``docs/readme-tables-record.json``; ``tests/dialog/test_readme_tables.py`` replays that subset
and fails when the code no longer gives those bytes (``dialog/experiments/readme_tables.py``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shlex
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from dialog.experiments.doc_tables import (  # noqa: E402
    BEGIN_LINE,
    README_BLOCKS,
    Plan,
    finding_verdict,
    findings_table,
    format_p,
    load_plan,
    report_findings,
    report_tables,
    results_table,
    splice,
    stamp,
    verdict_words,
)
from dialog.experiments.progress import SweepProgress, relay  # noqa: E402
from dialog.experiments.readme_tables import NAME as README  # noqa: E402
from dialog.experiments.readme_tables import RECORD_FILE as README_RECORD  # noqa: E402
from dialog.experiments.readme_tables import load_spec, readme_tables, run_readme, write_check  # noqa: E402
from dialog.experiments.record import RECORD_FILE, STATUS_DOCS, record_status, status_text, write_record, write_status  # noqa: E402
from dialog.experiments.runner import episode_specs  # noqa: E402
from dialog.experiments.suite import load_suite  # noqa: E402
from learning.errors import SettingsError, TeachbotError  # noqa: E402

CODE = ("learning", "dialog", "bullet_world", "robot", "pyproject.toml")
DEFAULT_PLAN = ROOT / "docs" / "experiments.toml"
DEMO_SHARE_COLUMNS = ("dt-iros", "dt-iros-v1", "dt-task", "dt-task-v1", "dt-task-env", "dt-task-env-v1", "dt-voi")
THESIS_DT = ("dt-iros", "dt-task", "dt-task-env")  # the columns of a demo-share table before any run


def git(*words: str) -> str:
    return subprocess.run(["git", *words], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()


def command_for(run, plan: Plan, results: Path, progress: bool = True) -> list[str]:
    shown = os.path.relpath(results, ROOT) if results.resolve().is_relative_to(ROOT) else str(results)
    words = ["teachbot", "regress", "--suite", run.suite, "--results", shown,
             "--progress-events" if progress else "--no-progress", "--json"]
    if load_suite(run.suite).kind == "episodes":  # other kinds (ch5, recipes): one run on their own data
        words += ["--data-seeds", *map(str, plan.data_seeds), "--seeds", *map(str, plan.seeds)]
    if run.strategies:
        words += ["--strategies", *run.strategies]
    return words


def planned_episodes(run, plan: Plan) -> int:
    """The episodes of one run of the plan (0 for a suite that is not an episodes suite: ch5, recipes)."""
    suite = load_suite(run.suite)
    if suite.kind != "episodes":
        return 0
    suite = suite.with_overrides(strategies=run.strategies or None, seeds=plan.seeds)
    return len(episode_specs(suite, Path("results"))) * len(plan.data_seeds)


def run_one(words: list[str], line: SweepProgress | None) -> subprocess.CompletedProcess:
    """Run one ``teachbot regress``; its episode events advance ``line``, its other messages are shown."""
    child = subprocess.Popen([sys.executable, "-m", "dialog.cli", *words[1:]], cwd=ROOT, text=True,
                             stdout=subprocess.PIPE, stderr=None if line is None else subprocess.PIPE)
    reader = None
    if line is not None:
        reader = threading.Thread(target=relay, args=(child.stderr, line, sys.stderr), daemon=True)
        reader.start()
    stdout = child.stdout.read() if child.stdout is not None else ""
    child.wait()
    if reader is not None:
        reader.join()
    return subprocess.CompletedProcess(child.args, child.returncode, stdout)


def code_dirty(allow_dirty: bool) -> bool:
    """Whether the code has uncommitted changes; refused unless ``allow_dirty`` (the stamps then say so)."""
    dirty = bool(git("status", "--porcelain", "--", *CODE))
    if dirty and not allow_dirty:
        raise SettingsError("the code has uncommitted changes (git status -- " + " ".join(CODE) + "): commit "
                            "first, so that the stamps name the code that made the tables, or give --allow-dirty")
    return dirty


def run_all(plan: Plan, only: list[str] | None, out: Path, allow_dirty: bool, progress: bool = True) -> dict:
    dirty = code_dirty(allow_dirty)
    manifest_path = out / "manifest.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() and only else {"runs": {}}
    manifest.update({"commit": git("rev-parse", "HEAD"), "dirty": dirty, "cores": os.cpu_count(),
                     "date": datetime.date.today().isoformat()})
    runs = [run for run in plan.runs if not only or run.suite in only]
    line = SweepProgress(sum(planned_episodes(run, plan) for run in runs)) if progress else None
    try:
        for run in runs:
            _run_and_record(run, plan, out, manifest, dirty, line)
    finally:
        if line is not None:
            line.close()
    manifest["wall_seconds"] = round(sum(r["wall_seconds"] for r in manifest["runs"].values()), 1)
    out.mkdir(parents=True, exist_ok=True)
    manifest_path.write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest


def _run_and_record(run, plan: Plan, out: Path, manifest: dict, dirty: bool, line: SweepProgress | None) -> None:
    """One run of the plan (its results folder emptied first), its wall time and episodes into ``manifest``."""
    say = print if line is None else line.note
    results = out / run.suite
    if results.exists():
        shutil.rmtree(results)
    words = command_for(run, plan, results, line is not None)  # as the stamps show it (results relative to ROOT)
    words_run = list(words)
    words_run[words_run.index("--results") + 1] = str(results)  # run with the full path
    say(f"$ {shlex.join(words)}")
    if line is not None:
        line.describe(run.suite if planned_episodes(run, plan) else f"{run.suite} (not episodes: not counted)")
    began = time.perf_counter()
    done = run_one(words_run, line)
    seconds = time.perf_counter() - began
    say(done.stdout[-2000:])
    if done.returncode != 0:
        raise SystemExit(f"experiments: '{shlex.join(words)}' failed with exit code {done.returncode}")
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    manifest["runs"][run.suite] = {"command": shlex.join(words), "wall_seconds": round(seconds, 1),
                                   "episodes": summary.get("episodes"), "commit": manifest["commit"],
                                   "dirty": dirty}
    say(f"  {run.suite}: {seconds:.0f} s")


def tables_from(plan: Plan, manifest: dict, out: Path, command: str = "make experiments") -> dict[str, str]:
    """Every table this run can write, keyed by block name, each with its stamp."""
    tables, replications, reports = {}, {}, {}
    for run in plan.runs:
        record = manifest["runs"].get(run.suite)
        if record is None:
            continue
        line = stamp({**manifest, "commit": record["commit"], "dirty": record["dirty"]}, record["command"])
        folder = out / run.suite
        figures = _copy_figures(run, folder, plan.data_seeds[0])
        if (folder / "replication.json").exists():
            replications[run.suite] = json.loads((folder / "replication.json").read_text())
            tables[f"{run.suite}:results"] = results_table(replications[run.suite]) + figures + "\n\n" + line
            tables[f"{run.suite}:findings"] = findings_table(replications[run.suite]) + "\n\n" + line
        else:
            reports[run.suite] = (folder / "report.md").read_text(encoding="utf-8")
            tables[f"{run.suite}:report"] = report_tables(reports[run.suite]) + figures + "\n\n" + line
    overall = stamp(manifest, command)
    tables["summary:findings"] = summary_findings(plan, replications, reports) + "\n\n" + overall
    tables["summary:demo-share"] = demo_shares(plan, replications) + "\n\n" + overall
    tables["summary:wall-times"] = wall_times(manifest) + "\n\n" + overall
    tables["summary:suites"] = suites_table(plan, manifest, replications, reports) + "\n\n" + overall
    return tables


def _copy_figures(run, folder: Path, data_seed: int) -> str:
    """The run's figures into docs/img/experiments (an episodes suite's from its first data seed's report)."""
    lines = []
    for name, target, caption in run.figures:
        source = folder / f"data-seed-{data_seed}" / name
        source = source if source.exists() else folder / name
        if source.exists():
            destination = ROOT / "docs" / "img" / "experiments" / target
            destination.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, destination)
            lines.append(f"![{caption}](img/experiments/{target})")
    return ("\n\n" + "\n\n".join(lines)) if lines else ""


def summary_findings(plan: Plan, replications: dict, reports: dict) -> str:
    """Item 7: every thesis finding of every suite in one table."""
    lines = ["| suite | finding | points its way on data seeds | pooled verdict (Holm p) |", "|---|---|---|---|"]
    for run in plan.runs:
        if run.suite in replications:
            rep = replications[run.suite]
            for finding in rep["findings"]:
                cells = [c for c in finding["by_data_seed"].values() if c["tested"]]
                pooled = finding["pooled"]
                verdict = finding_verdict(pooled) + (f" ({format_p(pooled['p_holm'])})" if pooled["tested"]
                                                     else f": {pooled['why']}")
                lines.append(f"| {run.suite} | {finding['id']}: {finding['text']} | "
                             f"{sum(c['direction'] for c in cells)} of {len(cells)} | {verdict} |")
        elif run.suite in reports:
            for finding in report_findings(reports[run.suite]):
                lines.append(f"| {run.suite} | {finding['id']}: {finding['text']} | (one data set) | "
                             f"{verdict_words(finding['holds'])} |")
    return "\n".join(lines)


def demo_shares(plan: Plan, replications: dict) -> str:
    """DT's demonstration share per condition beside the thesis's figure for that condition (§6.6), one column
    per DT strategy the runs played (the old presets and dt-voi too, where a plan runs them)."""
    shares = {}
    for key in plan.thesis_demo_share:
        suite, _, condition = key.partition("/")
        rows = next((c["strategies"] for c in replications.get(suite, {}).get("conditions", [])
                     if c["name"] == condition), [])
        shares[key] = {r["strategy"]: r["pooled"]["demo_share"] for r in rows}
    played = {name for share in shares.values() for name in share}
    columns = [name for name in DEMO_SHARE_COLUMNS if name in played] or list(THESIS_DT)
    lines = ["| suite / condition | thesis (DT) | " + " | ".join(columns) + " |", "|---|---:|" + "---:|" * len(columns)]
    for key, thesis in plan.thesis_demo_share.items():
        share = shares[key]
        lines.append(f"| {key} | {thesis:.0%} | " + " | ".join(
            f"{share[s]:.0%}" if s in share else "–" for s in columns) + " |")
    return "\n".join(lines)


def suites_table(plan: Plan, manifest: dict, replications: dict, reports: dict) -> str:
    """The README's table: each suite's size, wall time and how many of its findings hold (pooled)."""
    lines = ["| suite | episodes or runs | wall time | findings that hold (pooled over the data seeds) |",
             "|---|---:|---:|---|"]
    for run in plan.runs:
        record = manifest["runs"].get(run.suite)
        if record is None:
            continue
        if run.suite in replications:
            outcomes = [(f["id"], f["pooled"].get("holds", False)) for f in replications[run.suite]["findings"]
                        if f["pooled"]["tested"]]
        else:
            outcomes = [(f["id"], f["holds"]) for f in report_findings(reports.get(run.suite, ""))]
        held = [name for name, holds in outcomes if holds]
        lines.append(f"| {run.suite} | {record.get('episodes') or '–'} | {record['wall_seconds']:.0f} s | "
                     f"{len(held)} of {len(outcomes)}" + (f": {', '.join(held)}" if held else "") + " |")
    return "\n".join(lines)


def wall_times(manifest: dict) -> str:
    lines = ["| suite | command | episodes or runs | wall time |", "|---|---|---:|---:|"]
    for suite, record in manifest["runs"].items():
        lines.append(f"| {suite} | `{record['command']}` | {record.get('episodes') or '–'} | "
                     f"{record['wall_seconds']:.0f} s |")
    lines.append(f"| all | `make experiments` | | {manifest.get('wall_seconds', 0):.0f} s |")
    return "\n".join(lines)


def render(plan: Plan, manifest: dict, out: Path, command: str = "make experiments") -> list[str]:
    """Every table of the plan into its docs; ``command`` is what the summary tables' stamps name."""
    return write_blocks(plan, tables_from(plan, manifest, out, command))


def write_blocks(plan: Plan, tables: dict[str, str]) -> list[str]:
    """Each table between its markers in every doc of the plan; "doc: block" for each one written."""
    written = []
    for doc in plan.docs:
        path = ROOT / doc
        text, replaced = splice(path.read_text(encoding="utf-8"), tables)
        path.write_text(text, encoding="utf-8")
        written += [f"{doc}: {name}" for name in replaced]
    return written


def readme_run(plan: Plan, out: Path, render_only: bool, allow_dirty: bool, command: str) -> list[str]:
    """The README's demo and study tables (``plan.readme``): play their commands (unless ``render_only``), record
    the checked transcripts' hashes in docs/readme-tables-record.json, and write the blocks."""
    spec = load_spec(ROOT / str(plan.readme))
    if render_only:
        path = out / "readme.json"
        if not path.exists():
            raise SettingsError(f"{path}: no run of the README tables to render from (run without --render first)")
        return readme_blocks(plan, spec, json.loads(path.read_text()), out)
    meta = {"commit": git("rev-parse", "HEAD"), "dirty": code_dirty(allow_dirty), "date": datetime.date.today()
            .isoformat(), "cores": os.cpu_count(), "command": command}
    print(f"$ the README tables of {plan.readme} (results in {os.path.relpath(out, ROOT)})", flush=True)
    began = time.perf_counter()
    readme = run_readme(spec, out, meta, lambda line: print(line, flush=True))
    print(f"  {README}: {time.perf_counter() - began:.0f} s", flush=True)
    write_check(readme)
    return [*readme_blocks(plan, spec, readme, out), str(README_RECORD.relative_to(ROOT))]


def readme_blocks(plan: Plan, spec, readme: dict, out: Path) -> list[str]:
    """Write the README tables' blocks; refused when no doc of the plan has the markers of one of them."""
    written = write_blocks(plan, readme_tables(spec, readme, out))
    missing = [name for name in README_BLOCKS if not any(line.endswith(f": {name}") for line in written)]
    if missing:
        raise SettingsError(f"no doc of the plan ({', '.join(plan.docs)}) has the markers of "
                            + " or ".join(f"'{BEGIN_LINE.format(name=n)}'" for n in missing)
                            + "; put them (and their end markers) where the table goes, then rerun with --render")
    return written


def mark_record(manifest: dict) -> list[str]:
    """After a whole run of the docs' plan: the record file (commit and fingerprint, dialog/experiments/record.py)
    and the status in words in the README and docs/experiments.md."""
    write_record(manifest["commit"], manifest["date"])
    missing = write_status(status_text(record_status()))
    return [str(RECORD_FILE.relative_to(ROOT)), *(f"{doc}: record status" for doc in STATUS_DOCS if doc not in missing)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--plan", type=Path, default=DEFAULT_PLAN)
    parser.add_argument("--results", type=Path, default=ROOT / "results" / "experiments")
    parser.add_argument("--render", action="store_true", help="only rewrite the tables from the last run's files")
    parser.add_argument("--suites", nargs="+", default=None, help="only these runs of the plan")
    parser.add_argument("--allow-dirty", action="store_true", help="run with uncommitted code changes")
    parser.add_argument("--json", action="store_true", help="end with one JSON line: the manifest")
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress line (default: one line for the whole run on standard error)")
    args = parser.parse_args(argv)
    try:
        plan = load_plan(args.plan)
        if plan.readme:
            load_spec(ROOT / plan.readme)  # a bad file is one message now, not after an hour of suites
        names = [run.suite for run in plan.runs] + ([README] if plan.readme else [])
        unknown = sorted(set(args.suites or []) - set(names))
        if unknown:
            raise SettingsError(f"--suites: {', '.join(unknown)} not in {args.plan} ({', '.join(names)})")
        default = args.plan.resolve() == DEFAULT_PLAN
        plan_words = "" if default else f" --plan {os.path.relpath(args.plan.resolve(), ROOT)}"
        command = "make experiments" if default else f"python scripts/experiments.py{plan_words}"
        only = None if args.suites is None else [name for name in args.suites if name != README]
        manifest = None
        if only is None or only:
            manifest = suites_run(plan, args, only)
            for line in render(plan, manifest, args.results, command):
                print(f"wrote {line}")
        if plan.readme and (args.suites is None or README in args.suites):
            readme_command = command if args.suites is None else f"python scripts/experiments.py{plan_words} " \
                                                                  f"--suites {README}"
            for line in readme_run(plan, args.results / README, args.render, args.allow_dirty, readme_command):
                print(f"wrote {line}")
        if manifest and not args.render and not args.suites and default and not manifest.get("dirty"):
            for line in mark_record(manifest):
                print(f"wrote {line}")
    except TeachbotError as error:
        print(f"experiments: {error}", file=sys.stderr)
        return 2
    if manifest is not None:
        print(f"experiments: {len(manifest['runs'])} runs, {manifest.get('wall_seconds', 0):.0f} s, commit "
              f"{manifest['commit'][:10]}")
        if args.json:
            print(json.dumps(manifest))
    return 0


def suites_run(plan: Plan, args: argparse.Namespace, only: list[str] | None) -> dict:
    """The manifest of the suites' run: the last one's (``--render``), or a new run of ``only`` (None: all)."""
    if not args.render:
        return run_all(plan, only, args.results, args.allow_dirty, not args.no_progress)
    manifest_path = args.results / "manifest.json"
    if not manifest_path.exists():
        raise SettingsError(f"{manifest_path}: no run to render from (run without --render first)")
    return json.loads(manifest_path.read_text())


if __name__ == "__main__":
    sys.exit(main())
