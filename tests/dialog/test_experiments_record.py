"""``make experiments`` (scripts/experiments.py, dialog/experiments/doc_tables.py): the docs' results tables
are written from one run, between markers, each with a stamp (issue 26 item 6)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from dialog.experiments.doc_tables import (
    PARTS,
    README_BLOCKS,
    STAMP_PREFIX,
    SUMMARIES,
    blocks_in,
    load_plan,
    splice,
    unstamped_tables,
)
from learning.errors import SettingsError

ROOT = Path(__file__).resolve().parents[2]
RESULTS_DOCS = ("docs/experiments.md",)  # every table here is a result or says why it is not


def test_every_results_table_in_the_docs_is_generated_and_stamped():
    for doc in RESULTS_DOCS:
        text = (ROOT / doc).read_text(encoding="utf-8")
        assert blocks_in(text), f"{doc} has no generated blocks"
        assert unstamped_tables(text) == [], f"{doc}: tables (header lines) outside a stamped block"


def test_the_readme_suite_table_is_generated_and_stamped():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index("## What the experiments show")
    section = text[start:text.index("\n## ", start + 1)]
    assert "summary:suites" in blocks_in(section)
    assert unstamped_tables(section) == []


def test_every_block_the_docs_name_is_one_the_plan_can_write():
    plan = load_plan(ROOT / "docs" / "experiments.toml")
    writable = set(SUMMARIES) | (set(README_BLOCKS) if plan.readme else set())
    writable |= {f"{run.suite}:{part}" for run in plan.runs for part in PARTS}
    for doc in plan.docs:
        names = blocks_in((ROOT / doc).read_text(encoding="utf-8"))
        assert set(names) <= writable, f"{doc}: blocks no run of the plan writes: {set(names) - writable}"


def test_splice_replaces_only_between_the_markers():
    text = "before\n<!-- experiments:begin a:results -->\nold\n<!-- experiments:end a:results -->\nafter\n"
    new, replaced = splice(text, {"a:results": "| x |\n|---|\n| 1 |", "b:results": "unused"})
    assert replaced == ["a:results"]
    assert new.startswith("before\n") and new.endswith("after\n") and "old" not in new and "| 1 |" in new
    assert splice(new, {"a:results": "| x |\n|---|\n| 1 |"})[0] == new  # rewriting is idempotent


def test_an_unstamped_or_unmarked_table_is_found():
    stamped = f"<!-- experiments:begin a:results -->\n| x |\n|---|\n{STAMP_PREFIX} ...</sub>\n" \
              "<!-- experiments:end a:results -->\n"
    assert unstamped_tables(stamped) == []
    assert unstamped_tables(stamped.replace(STAMP_PREFIX, "typed by hand")) == [5]
    loose = "text\n\n| y |\n|---|\n| 2 |\n"
    assert unstamped_tables(loose) == [3]
    assert unstamped_tables(loose.replace("\n\n", "\n\n<!-- not-results: a list of costs -->\n")) == []


def test_broken_markers_and_plans_get_one_message(tmp_path):
    with pytest.raises(SettingsError, match="has no"):
        blocks_in("<!-- experiments:begin a:results -->\n")
    with pytest.raises(SettingsError, match="twice"):
        blocks_in("<!-- experiments:begin a:x -->\n<!-- experiments:end a:x -->\n" * 2)
    plan = tmp_path / "plan.toml"
    plan.write_text('docs = []\n[[run]]\nsuite = "smoke"\nfigure = []\n')
    with pytest.raises(SettingsError, match="unknown keys figure"):
        load_plan(plan)
    plan.write_text("docs = []\n")
    with pytest.raises(SettingsError, match="no \\[\\[run\\]\\]"):
        load_plan(plan)


def test_a_run_writes_stamped_tables_from_its_own_files(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("# doc\n" + "".join(f"<!-- experiments:begin {n} -->\nSTALE TEXT\n<!-- experiments:end {n} -->\n"
                                       for n in ("smoke:results", "smoke:findings", "summary:wall-times")))
    plan = tmp_path / "plan.toml"
    plan.write_text(f'docs = ["{doc}"]\ndata_seeds = [0]\nseeds = [0]\n[[run]]\nsuite = "smoke"\n')
    results = tmp_path / "results"
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "experiments.py"), "--plan", str(plan),
                           "--results", str(results), "--allow-dirty", "--json"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    manifest = json.loads(done.stdout.strip().splitlines()[-1])
    assert manifest["runs"]["smoke"]["episodes"] == 12 and manifest["cores"] >= 1
    progress = [line for line in done.stderr.splitlines() if line.startswith("episodes ")]
    assert progress and progress[-1].startswith("episodes 12/12 (100%)"), done.stderr  # the run's one line
    assert all("/12 " in line for line in progress) and "teachbot-progress" not in done.stderr + done.stdout
    text = doc.read_text()
    assert "STALE TEXT" not in text and unstamped_tables(text) == []
    replication = json.loads((results / "smoke" / "replication.json").read_text())
    dt = next(r for r in replication["conditions"][0]["strategies"] if r["strategy"] == "dt-task")
    assert f"| dt-task | {dt['pooled']['mean']:.3f} ± {dt['pooled']['error']:.3f} |" in text
    again = subprocess.run([sys.executable, str(ROOT / "scripts" / "experiments.py"), "--plan", str(plan),
                            "--results", str(results), "--render"], capture_output=True, text=True, timeout=120)
    assert again.returncode == 0 and doc.read_text() == text  # rendering again from the files changes nothing
