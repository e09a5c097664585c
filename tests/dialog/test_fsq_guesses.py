"""The FSQ-guess probe (issue 49 item 3), small: it changes no decision and records only open-FSQ states."""

import numpy as np
import pytest

from dialog.experiments.fsq_guesses import TARGETS, dominated, guess_table, horizon_table
from dialog.experiments.whatif_calibration import CalibrationTask, calibration_specs, play
from learning.whatif.feature_guesses import GUESSES

SMALL = (("objects_per_scene", 8), ("pool_size", 24), ("test_size", 16))


@pytest.fixture(scope="module")
def episodes():
    spec = calibration_specs(["dt-task-env"], 101, 1, [41], turns=8, plan=SMALL)[0]
    return (play(CalibrationTask(spec, accuracy_what_if=False, feature_guesses=True, horizon=True)),
            play(CalibrationTask(spec, accuracy_what_if=False, record=False)))


def test_the_probe_changes_no_decision(episodes):
    probed, plain = episodes
    assert probed["actions"] == plain["actions"] and probed["accuracy"] == plain["accuracy"]


def test_records_cover_the_open_turns_after_the_first_example(episodes):
    probed, _ = episodes
    records = probed["feature_guesses"]
    assert records, "dt-task-env keeps the FSQ open in this episode"
    asked = [i + 1 for i, a in enumerate(probed["actions"]) if a["kind"] == "feature"]
    assert all(r["turn"] < min(asked, default=99) for r in records)
    for r in records:
        assert set(r["guesses"]) == set(GUESSES) and r["examples"] >= 1
        assert len(r["realised"]) == 4 and -1 <= r["realised_accuracy"] <= 1
        assert dominated(r, [-1.0] * 4) == (len(r["instance"]) > 0)  # anything beats a change of -1 everywhere


def test_the_table_is_the_records_means(episodes):
    records = episodes[0]["feature_guesses"]
    rows = guess_table(records)
    assert len(rows) == len(GUESSES) * len(TARGETS)
    row = next(r for r in rows if r["guess"] == "union" and r["target"] == "accuracy")
    p = np.array([r["guesses"]["union"]["predicted_accuracy"] for r in records])
    q = np.array([r["realised_accuracy"] for r in records])
    assert row["mae"] == pytest.approx(np.abs(p - q).mean()) and row["n"] == len(records)


def test_the_horizon_reads_the_same_guesses_over_more_evidence_and_the_end(episodes):
    records = episodes[0]["feature_guesses"]
    for r in records:
        assert r["horizon"]["copies"] >= 1 and 0 <= r["horizon"]["m"] <= 8
        assert len(r["realised_by_end"]) == 4 and -1 <= r["realised_accuracy_by_end"] <= 1
        for guess in GUESSES:
            assert len(r["guesses"][guess]["horizon"]) == 4
    rows = horizon_table(records)
    assert {row["reading"] for row in rows} == {"one step", "horizon"}
    assert all(row["n"] <= len(records) for row in rows)
