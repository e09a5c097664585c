"""scripts/bench_decision.py: the JSON row splits the fast decision's CPU time by whether the feature query is open,
and times ES alone on the open states (issue 28's floors)."""

import importlib.util
import json
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "bench_decision.py"


def test_the_row_has_the_split_by_feature_query_and_es_alone(capsys):
    spec = importlib.util.spec_from_file_location("bench_decision", SCRIPT)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    assert bench.main(bench._parse(["--objects", "6", "--train", "12", "--states", "6", "--repeats", "1",
                                    "--json"])) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    (row,) = json.loads(lines[-1])
    assert lines[-2].lstrip().startswith("cpu by state: FSQ closed")
    assert row["same_action"] >= 0.5 and row["states"] == 6
    open_states = row["feature_query_open"]
    assert 0 < open_states < 6, "the seeded states should mix open and answered feature queries"
    for key in ("fast_cpu_ms_fsq_closed", "fast_cpu_ms_fsq_open", "es_cpu_ms"):
        assert row[key]["p50"] > 0 and row[key]["p95"] >= row[key]["p50"]
