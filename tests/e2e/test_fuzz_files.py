"""``scripts/fuzz_files.py``: mutated files and hostile output paths against the real commands that read them."""

import argparse
import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10
    import tomli as tomllib

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"
sys.path.insert(0, str(SCRIPTS))
import _fuzz_files_kinds as kinds  # noqa: E402
from fuzz_files import COUNTS, Case, Fuzzer, Kind, bytes_lost, refused, snapshot  # noqa: E402

#: another engineer hardens the policy and weights files (issue 24, item 5) in parallel
OTHER_AREAS = ("policy", "policy-npz", "weights")


def test_lost_bytes_count_complete_lines_that_are_gone_and_not_kept_elsewhere(tmp_path):
    record = tmp_path / "r.jsonl"
    record.write_bytes(b'{"a": 1}\n{"b": 2}\n{"c"')
    before = snapshot(tmp_path, "*.jsonl")
    record.write_bytes(b'{"a": 1}\n{"b": 2}\n{"c": 3}\n')  # a torn tail repaired and a line added: nothing lost
    assert bytes_lost(tmp_path, before) == 0
    record.write_bytes(b'{"a": 1}\n')
    assert bytes_lost(tmp_path, before) == 9  # the second line is gone
    (tmp_path / "r.jsonl.superseded-1").write_bytes(b'{"a": 1}\n{"b": 2}\n{"c"')
    assert bytes_lost(tmp_path, before) == 0  # kept whole under another name


def test_a_study_record_counts_as_refused_only_when_status_marks_its_session_damaged():
    kind = Kind("questionnaire", "study", "x", [], [], damaged="damaged: P01 session 1 (dt-task)")
    case = Case(0, "questionnaire", "Likert 99", True, results=[([], 0, "sessions: 3 done")])
    assert not refused(case, kind)
    case.results = [([], 0, "damaged: P01 session 1 (dt-task): d/P01/1-dt-task-questionnaire.jsonl: line 2: ...")]
    assert refused(case, kind)
    assert refused(Case(0, "suite", "x", True, results=[([], 2, "teachbot regress: ...")]), None)


def test_a_wrong_type_mutation_gives_a_field_another_type(tmp_path):
    path = tmp_path / "s.toml"
    original = {"name": "smoke", "seeds": [0], "costs": {"label": 1, "free": True}}
    types = {p: type(v) for p, v in kinds._leaves(original)}
    for seed in range(8):
        path.write_text(kinds.dump_toml(original))
        assert tomllib.loads(path.read_text()) == original  # the dump reads back as it was
        kinds.wrong_type()(path, np.random.default_rng(seed))
        changed = {p: type(v) for p, v in kinds._leaves(tomllib.loads(path.read_text()))}
        assert any(changed.get(p) != t for p, t in types.items())


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    result = subprocess.run([sys.executable, str(SCRIPTS / "fuzz_files.py"), "--cases", "26", "--seed", "4", "--json"],
                            capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_a_small_run_covers_every_kind_and_finds_nothing_in_the_file_and_path_readers(small_run):
    assert small_run["cases"] == 26 and set(COUNTS) <= set(small_run)
    assert sorted(small_run["per_kind"]) == sorted(
        ["study", "suite", "weights", "policy", "policy-npz", "kitchen", "task", "transcript", "replay",
         "study-transcript", "questionnaire", "study-note", "consent-record", "practice-transcript", "consent-text",
         "demonstrations", "generator", "generated-kitchen", "paths"])
    found = {kind: {name: counts[name] for name in COUNTS if counts[name]}
             for kind, counts in small_run["per_kind"].items() if kind not in OTHER_AREAS}
    assert not any(found.values()), (found, small_run["examples"])


def test_the_same_seed_mutates_the_same_files_the_same_way(tmp_path):
    options = argparse.Namespace(cases=26, seed=7, timeout=60.0, workers=1)
    fuzzer = Fuzzer(options, tmp_path)
    kind_list = fuzzer.setup()
    by_name = {kind.name: kind for kind in kind_list}
    runs = []
    for attempt in ("a", "b"):
        mutated = []
        for spec in fuzzer.plan(kind_list):
            if spec[1] == "paths":
                continue
            folder = tmp_path / attempt / str(spec[0])
            case = fuzzer.prepare(spec, by_name, folder)
            mutated.append((case.kind, case.mutation, case.breaks_rule, _content(folder / by_name[case.kind].target)))
        runs.append(mutated)
    assert runs[0] == runs[1] and len(runs[0]) == 25


def _content(path: Path):
    """A mutated file's bytes; a link's target, a FIFO and a removed file by kind (reading a FIFO would block)."""
    if path.is_symlink():
        return ("link", os.readlink(path))
    if not path.exists():  # a record removed (the consent record, its sessions kept)
        return ("missing",)
    return ("fifo",) if stat.S_ISFIFO(path.stat().st_mode) else path.read_bytes()


def test_the_replay_and_study_mutations_of_issue_42_break_their_files_the_stated_way(tmp_path):
    rng = np.random.default_rng(0)
    record = {"turn": 1, "answer": {"lines": ["a fruit"], "kind": "answer"}}
    path = tmp_path / "t.jsonl"
    for rules in (kinds.REPLAY_RULES, kinds.STUDY_TRANSCRIPT_RULES):
        names = dict(rules)
        path.write_text(json.dumps({"session": {"study": {"software": "teachbot 0.1.0"}}}) + "\n" +
                        json.dumps(record) + "\n" + json.dumps(record | {"turn": 2}) + "\n")
        names["an answer line a lone surrogate"](path, rng)
        assert '"lines": ["\\ud800zz"]' in path.read_text()
    names["torn after a turn, beside the questionnaire"](path, rng)
    assert not path.read_bytes().endswith(b"\n") or path.read_bytes().count(b"\n") < 3
    for name, shown in (("a link to /dev/zero", ("link", "/dev/zero")), ("a FIFO", ("fifo",))):
        dict(kinds.REPLAY_RULES)[name](path, rng)
        assert _content(path) == shown
