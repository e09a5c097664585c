"""A resumed session reports its whole time: the recorded part before the interruption and the part after."""

import io
import json
import re

import pytest

from dialog.cli import build_parser
from dialog.commands import teach

pytestmark = pytest.mark.e2e


def _teach(argv, answers: str) -> str:
    out = io.StringIO()
    args = build_parser().parse_args(["teach", *argv])
    assert teach.run(args, input_stream=io.StringIO(answers), output_stream=out) == 0
    return out.getvalue()


def test_a_resumed_person_session_counts_the_time_before_the_interruption(tmp_path):
    path = tmp_path / "session.jsonl"
    first = _teach(["--strategy", "passive", "--turns", "4", "--budget", "10", "--change-every", "2",
                    "--transcript", str(path), "--no-pictures"], "skip\nskip\nquit\n")
    assert "Session saved after 2 of 4 turns" in first
    lines = path.read_text().splitlines()
    last = json.loads(lines[-1])
    assert last["turn"] == 2
    last["ended"] = round(last["ended"] + 100.0, 3)  # as if the teacher had taken 100 s more before quitting
    path.write_text("\n".join([*lines[:-1], json.dumps(last)]) + "\n")

    resumed = _teach(["--resume", str(path), "--no-pictures"], "skip\nskip\n")
    found = re.search(r"([\d.]+) s in all \(([\d.]+) s before the resume, ([\d.]+) s after\)", resumed)
    assert found, resumed[-600:]
    total, before, after = map(float, found.groups())
    assert before == pytest.approx(last["ended"], abs=0.05) and before >= 100
    assert total == pytest.approx(before + after, abs=0.11) and after < 60
