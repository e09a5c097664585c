"""scripts/bench_pool.py: one pool for every data seed against a fresh pool each, the same episodes both ways."""

import json

from tests.scripts import load_script


def test_both_sides_play_the_same_episodes_and_report_their_wall_time(capsys):
    bench = load_script("bench_pool")
    assert bench.main(["--suite", "smoke", "--data-seeds", "0", "--strategies", "passive", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["transcripts_identical"] is True and result["speedup"] > 0
    assert set(result["wall_s"]) == {"fresh-pools", "one-pool"} and all(v > 0 for v in result["wall_s"].values())
