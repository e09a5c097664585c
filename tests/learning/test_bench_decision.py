"""scripts/bench_decision.py: the JSON row splits the fast decision's CPU time by whether the feature query is open,
times ES alone on the open states and the time inside LAPACK (issue 28's floors)."""

import json

from tests.scripts import load_script


def _load():
    return load_script("bench_decision")


def test_the_row_has_the_split_by_feature_query_and_es_alone(capsys):
    bench = _load()
    assert bench.main(bench._parse(["--objects", "6", "--train", "12", "--states", "6", "--repeats", "1",
                                    "--json"])) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    (row,) = json.loads(lines[-1])
    assert lines[-3].lstrip().startswith("cpu by state: FSQ closed")
    assert lines[-2].lstrip().startswith("inside LAPACK: FSQ closed")
    assert row["same_action"] >= 0.5 and row["states"] == 6
    open_states = row["feature_query_open"]
    assert 0 < open_states < 6, "the seeded states should mix open and answered feature queries"
    for key in ("fast_cpu_ms_fsq_closed", "fast_cpu_ms_fsq_open", "es_cpu_ms"):
        assert row[key]["p50"] > 0 and row[key]["p95"] >= row[key]["p50"]
    for group in ("closed", "open"):  # a part of the decision's time, never more than it
        inside, whole = row[f"lapack_cpu_ms_fsq_{group}"], row[f"fast_cpu_ms_fsq_{group}"]
        assert 0 < inside["p50"] <= inside["p95"] and inside["p95"] <= 2 * whole["p95"]


def test_the_lapack_timer_counts_only_inside_the_block_and_restores_the_names():
    import numpy as np

    import learning.whatif.laplace as laplace

    bench = _load()
    before, solve = laplace.spotrf, np.linalg.solve
    matrix = np.eye(200, dtype=np.float32) * 2.0
    with bench.lapack_timer() as inside:
        for _ in range(50):
            laplace.spotrf(matrix, lower=1)
    assert inside[0] > 0
    assert laplace.spotrf is before and np.linalg.solve is solve
    counted = inside[0]
    laplace.spotrf(matrix, lower=1)
    assert inside[0] == counted, "calls after the block are not counted"
