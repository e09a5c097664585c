"""The README's demo and study tables still describe the code (issue 51 item 2; dialog/experiments/readme_tables.py).

`make readme-tables` (python scripts/experiments.py --suites readme) makes them from real runs and records the
SHA-256 of a cheap subset's transcripts (one seed per demo strategy, one simulated participant) in
docs/readme-tables-record.json. This test plays that subset again: a commit that changes what the demo or the
study decides fails here until the tables are rerun."""

import json

import pytest

from dialog.experiments.doc_tables import STAMP_PREFIX, blocks_in, unstamped_tables
from dialog.experiments.readme_tables import (
    RECORD_FILE,
    REGENERATE,
    ROOT,
    SPEC_FILE,
    checked_runs,
    demo_table,
    load_spec,
    table_columns,
)
from learning.errors import DataFileError, SettingsError


@pytest.mark.e2e
def test_the_readme_tables_were_made_by_the_code_as_it_is(tmp_path):
    spec = load_spec()
    record = json.loads(RECORD_FILE.read_text(encoding="utf-8"))
    now = checked_runs(spec, tmp_path)
    then = record["checked"]
    moved = sorted(label for label in set(now) | set(then) if now.get(label) != then.get(label))
    assert not moved, (f"the README's demo and study tables were made at commit {record['commit'][:10]} "
                       f"({record['date']}), but the code now gives other transcripts for {', '.join(moved)}: "
                       f"rerun them with `{REGENERATE}` (python scripts/experiments.py --suites readme) and commit "
                       f"README.md, {RECORD_FILE.relative_to(ROOT)} and the study figure")


def test_the_readme_has_both_blocks_stamped_and_no_typed_table_beside_them():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert {"summary:demo", "summary:study"} <= set(blocks_in(text))
    sections = (("## Install and run", "## Teach the robot"), ("## Run a user study", "## Use the learning core"))
    for start, end in sections:
        section = text[text.index(start):text.index(end)]
        assert unstamped_tables(section) == [], f"README.md, {start}: a table outside a stamped block"
    record = json.loads(RECORD_FILE.read_text(encoding="utf-8"))
    assert f"{STAMP_PREFIX} at commit {record['commit'][:10]}" in text  # the blocks are the recorded run's


def test_make_demo_plays_the_episode_the_table_measures():
    spec = load_spec()
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    demo = next(line for line in makefile.splitlines() if "teachbot demo" in line)
    assert " ".join(spec.demo_options) in demo, f"Makefile's demo ({demo.strip()}) differs from {SPEC_FILE.name}"


def test_a_bad_spec_gets_one_message(tmp_path):
    good = SPEC_FILE.read_text(encoding="utf-8")
    bad = tmp_path / "readme.toml"
    for old, new, message in (('checked_seed = 0', 'checked_seed = 9', "not one of the seeds"),
                              ('checked_participant = "P01"', 'checked_participant = "X"', "is not one of P01"),
                              ('"--turns"', '"--seed"', "must not give --seed"),
                              ('file = "dialog/data/studies/example.toml"', 'file = "no.toml"', "not a file"),
                              ('[study]', '[studies]', "unknown field")):
        bad.write_text(good.replace(old, new))
        with pytest.raises(DataFileError, match=message):
            load_spec(bad)


def test_tables_are_cut_from_the_report_and_the_rows():
    report = ("# x\n\n| condition | n | extra | sd |\n|---|---|---|---|\n| a | 6 | 1 | 0.1 |\n| b | 6 | 2 | 0.2 |\n\n"
              "| measure | conditions | n |\n|---|---|---|\n| final accuracy | a vs b | 6 |\n| ease | a vs b | 6 |\n")
    assert table_columns(report, "condition", ("condition", "sd")) == [
        "| condition | sd |", "|---|---|", "| a | 0.1 |", "| b | 0.2 |"]
    assert table_columns(report, "measure", ("measure", "n"), ("final accuracy",))[2:] == ["| final accuracy | 6 |"]
    with pytest.raises(SettingsError, match="no column 'mean'"):
        table_columns(report, "condition", ("mean",))
    spec = load_spec()
    rows = [{"strategy": s, "seed": seed, "accuracy": 0.5 + seed / 10} for s, _ in spec.strategies for seed in (1, 0)]
    table = demo_table(spec, {"demo": rows})
    assert "| `dt-task` (the demo's) | 0.500 0.600 | 0.550 |" in table and "S = 0, 1" in table
