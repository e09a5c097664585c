"""The record in the docs says whether it still describes the code (issue 39 item 7; dialog/experiments/record.py).

tests/dialog/test_fingerprint.py keeps dialog/data/fingerprint-transcripts.json equal to what the code decides;
this test keeps the README's and docs/experiments.md's words about the record equal to what comparing that file
with the record's stored fingerprint says. A commit that moves a decision fails here until `make experiments`
is rerun or the caveat names what is stale (`python -m dialog.experiments.record --write`)."""

import json

from dialog.experiments.record import (
    ROOT,
    STATUS_DOCS,
    blocks,
    record_status,
    rewrite,
    status_text,
    write_record,
)


def test_the_docs_say_what_the_record_describes_now():
    words = status_text(record_status())
    for doc in STATUS_DOCS:
        found = blocks((ROOT / doc).read_text(encoding="utf-8"))
        assert found == [words], (f"{doc} says {found} about the record, but comparing its fingerprint with the "
                                  f"code's says: {words!r}. Rerun `make experiments`, or run "
                                  "`python -m dialog.experiments.record --write` to say what is stale.")


def test_a_moved_decision_makes_exactly_its_strategy_stale(tmp_path):
    hashes = tmp_path / "hashes.json"
    episodes = {"ch7/dt-task/d0": {"transcript": "a", "series": "x"},
                "ch7/active/d0": {"transcript": "b", "series": "y"}}
    hashes.write_text(json.dumps({"episodes": episodes}))
    record = tmp_path / "record.json"
    write_record("0123456789abcdef", "2026-12-04", hashes, record)
    current = record_status(record, hashes)
    assert current.current and "describes the code" in status_text(current)
    episodes["ch7/dt-task/d0"]["transcript"] = "moved"
    episodes["ch7/dt-voi/d0"] = {"transcript": "new", "series": "z"}  # a strategy the record never ran: not stale
    hashes.write_text(json.dumps({"episodes": episodes}))
    stale = record_status(record, hashes)
    assert stale.stale_strategies() == ["dt-task"]
    assert "stale for dt-task" in status_text(stale) and "1 of 2" in status_text(stale)


def test_every_strategy_the_record_runs_is_fingerprinted():
    """A strategy outside the fingerprint could change its decisions without the record going stale."""
    from dialog.experiments.doc_tables import load_plan
    from dialog.experiments.fingerprint import EPISODES_FILE
    from dialog.experiments.suite import load_suite
    from learning.datafiles import read_toml

    fingerprinted = {s for group in read_toml(EPISODES_FILE, "fingerprint")["group"] for s in group["strategies"]}
    for plan_file in ("docs/experiments.toml",):
        plan = load_plan(ROOT / plan_file)
        for run in plan.runs:
            suite = load_suite(run.suite)
            if suite.kind != "episodes":
                continue
            missing = set(run.strategies or suite.strategies) - fingerprinted
            assert not missing, f"{plan_file} runs {sorted(missing)} in {run.suite}, which {EPISODES_FILE.name} lacks"


def test_rewrite_replaces_only_the_block():
    text = "before\n<!-- record-status:begin -->\nold\n<!-- record-status:end -->\nafter"
    assert rewrite(text, "new") == "before\n<!-- record-status:begin -->\nnew\n<!-- record-status:end -->\nafter"
