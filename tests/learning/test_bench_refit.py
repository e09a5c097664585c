"""scripts/bench_refit.py: its last line has the shape issue 28 asks for, and the update equals the fresh fit."""

import json

from tests.scripts import load_script


def test_the_last_line_is_the_rows_and_the_two_growth_exponents(capsys):
    bench = load_script("bench_refit")
    assert bench.main(bench._parse(["--sizes", "30", "500", "600", "--repeats", "1", "--json"])) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    result = json.loads(lines[-1])
    assert list(result) == ["rows", "incremental_exponent", "fresh_exponent"]
    assert [row["n"] for row in result["rows"]] == [30, 500, 600]
    assert all(list(row) == ["n", "incremental_ms", "fresh_ms"] and row["incremental_ms"] > 0 and row["fresh_ms"] > 0
               for row in result["rows"])
    assert isinstance(result["incremental_exponent"], float) and isinstance(result["fresh_exponent"], float)
    largest = float(lines[-2].rsplit("largest |dp| ", 1)[1])
    assert largest < 1e-6  # the update is the fresh fit within the Newton tolerance
