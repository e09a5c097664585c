"""``scripts/fuzz_web.py``: hostile page messages against real ``--web`` sessions (a study run, teach sessions)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from dialog.web.messages import Asked, decode, read_message, read_screen
from learning.errors import MessageError

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"
sys.path.insert(0, str(SCRIPTS))
from _fuzz_web_messages import Hostile  # noqa: E402

CONCEPTS = ["main dish", "snack", "fruit", "beverage"]
QUESTIONS = [
    {"id": 4, "expects": "label", "concepts": CONCEPTS, "objects": 12, "features": []},
    {"id": 5, "expects": "demo", "concepts": CONCEPTS, "objects": 12, "features": []},
    {"id": 6, "expects": "feature", "concepts": CONCEPTS, "objects": 12,
     "features": [{"number": "1"}, {"number": "1.1"}, {"number": "2"}]},
]
SCREENS = [{"id": 9, "items": []},
           {"id": 10, "items": [{"kind": "likert", "low": 1, "high": 7}, {"kind": "text"}]}]


def asked(question: dict) -> Asked:
    return Asked(question["id"], question["expects"], tuple(question["concepts"]), question["objects"],
                 frozenset(row["number"] for row in question["features"]))


def test_every_hostile_message_breaks_a_rule_the_server_states():
    """The corpus holds no valid answer: each message is refused in-process (so a count of silent accepts in a
    fuzz run is the server's, not the corpus's), and the same seed gives the same messages."""
    hostile = Hostile(np.random.default_rng(11))
    categories = set()
    for n in range(3000):
        question, screen = QUESTIONS[n % 3], SCREENS[(n // 4) % 2]
        category, raw = hostile.for_screen(screen) if n % 4 == 0 else hostile.for_question(question)
        categories.add(category)
        with pytest.raises(MessageError):
            message = decode(raw)
            if message.get("type") == "screen":
                read_screen(message, screen if n % 4 == 0 else None)
            else:
                read_message(message, asked(question) if n % 4 else None, lambda x, y: 0)
    assert {"json", "type", "numbers", "nesting", "text", "ids", "fields", "size", "screen text",
            "screen scale"} <= categories
    first = [Hostile(np.random.default_rng(3)).for_question(QUESTIONS[0]) for _ in range(5)]
    assert first == [Hostile(np.random.default_rng(3)).for_question(QUESTIONS[0]) for _ in range(5)]


@pytest.mark.e2e
def test_a_short_fuzz_run_finds_no_traceback_hang_silent_accept_or_lost_byte():
    run = subprocess.run([sys.executable, str(SCRIPTS / "fuzz_web.py"), "--messages", "250", "--per-stop", "25",
                          "--seed", "5", "--json"], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    assert summary["messages"] >= 250 and summary["sessions"] >= 1 and summary["screens"] >= 1
    assert (summary["tracebacks"], summary["hangs"], summary["silent_accepts"], summary["bytes_lost"]) == \
        (0, 0, 0, 0), summary["examples"]
    assert summary["refusals"] == summary["messages"] - summary["closed_oversized"]
    assert len(run.stderr.strip().splitlines()) >= summary["sessions"]  # a progress line per session
