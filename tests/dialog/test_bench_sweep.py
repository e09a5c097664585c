"""scripts/bench_sweep.py: turns per CPU-second of the frozen sweep on this tree and an earlier commit, one run."""

import json
import subprocess

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


def _has(commit: str) -> bool:
    bench = _load()
    return subprocess.run(["git", "-C", str(bench.ROOT), "cat-file", "-e", f"{commit}^{{commit}}"],
                          capture_output=True, check=False).returncode == 0


@pytest.mark.skipif(not _has("a844680"), reason="needs the pinned commit a844680 in the git history (not shallow)")
def test_one_quick_episode_runs_on_the_pinned_commit_too(capsys):
    """Issue 51: a844680's Condition has no until_budget_spent; it gets only the fields the episode sets."""
    bench = _load()
    assert bench.main(bench._parse(["--quick", "--episodes", "1", "--json"])) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert report["against"]["commit"] == "a844680" and report["episodes"] == 1
    assert report["this"]["turns"] == report["against"]["turns"] == bench.QUICK_TURNS
    assert report["ratio"] > 0


def test_the_episodes_go_as_plain_data_with_this_trees_defaults_beside_them():
    bench = _load()
    rows = bench.episode_rows(quick=True)
    assert [row["suite"] for row in rows] == ["fingerprint-ch7-time-constrained", "fingerprint-ch6-static-static"]
    assert rows[0]["condition"]["turns"] == bench.QUICK_TURNS and rows[1]["condition"]["objects_per_scene"] == 55
    assert "transcript" not in rows[0] and json.dumps(rows)  # plain data: JSON as it is
    assert bench.episode_rows(quick=True, count=1) == rows[:1]
    defaults = bench.field_defaults()
    assert defaults["Condition"]["until_budget_spent"] is False and defaults["EpisodeSpec"]["weights"] is None
    assert "name" not in defaults["Condition"]  # a field without a default is always sent


def test_a_field_the_code_lacks_is_refused_not_dropped():
    bench = _load()
    rows = bench.episode_rows(quick=True, count=1)
    rows[0]["condition"]["until_time_runs_out"] = True
    with pytest.raises(SystemExit) as stopped:
        bench.play(bench.ROOT, rows, "this tree")
    assert str(stopped.value) == ("bench_sweep: the episodes did not run on this tree: episode 1 (fingerprint-ch7-"
                                  "time-constrained/dt-task) sets until_time_runs_out=True, which this code's "
                                  "Condition does not have, so it cannot play the same episode")


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
    with pytest.raises(SystemExit):
        bench._parse(["--episodes", "0"])
    assert "--episodes must be a whole number of at least 1, got 0" in capsys.readouterr().err
