"""scripts/bench_sweep.py: turns per CPU-second of the frozen sweep on this tree and an earlier commit, one run."""

import json

import pytest

from tests.scripts import load_script


def _load():
    return load_script("bench_sweep")


def test_quick_run_against_head_reports_both_sides_and_their_ratio(capsys):
    bench = _load()
    assert bench.main(bench._parse(["--quick", "--against", "HEAD", "--json"])) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert report["episodes"] == 2 and report["rounds"] == 1 and report["quick"] is True
    for side in ("this", "against"):
        row = report[side]
        assert row["turns"] == 2 * bench.QUICK_TURNS  # both sides played every turn of both episodes
        assert row["cpu_seconds"] > 0 and row["turns_per_cpu_second"] > 0 and len(row["per_round"]) == 1
    assert report["ratio"] == pytest.approx(report["this"]["turns_per_cpu_second"]
                                            / report["against"]["turns_per_cpu_second"], abs=0.01)


def test_the_frozen_list_is_a844680s_ch6_static_and_ch7_episodes():
    rows = _load().episode_rows(quick=False)
    assert len(rows) == 11 + 4 * 5
    assert {row["task"] for row in rows} == {"pack-lunchbox", "prepare-lunch"}
    assert sum(row["condition"]["turns"] for row in rows) == 11 * 120 + 5 * (40 + 150 + 40 + 150)


@pytest.mark.parametrize("argv, fragment", [
    (["--against", "no-such-commit-xyz"], "unknown commit 'no-such-commit-xyz'"),
    (["--against=-p"], "unknown commit '-p'"),
])
def test_an_unknown_commit_gets_one_line(argv, fragment):
    bench = _load()
    with pytest.raises(SystemExit) as stopped:
        bench.main(bench._parse(argv))
    message = str(stopped.value)
    assert fragment in message and "\n" not in message and "a hash, tag or branch" in message


def test_rounds_below_one_are_refused(capsys):
    bench = _load()
    with pytest.raises(SystemExit):
        bench._parse(["--rounds", "0"])
    assert "--rounds must be a whole number of at least 1" in capsys.readouterr().err
