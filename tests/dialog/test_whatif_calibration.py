"""What-if calibration (issue 49 item 2), small: the recorder changes no decision and its records add up."""

import numpy as np
import pytest

from dialog.experiments.whatif_calibration import (
    KINDS,
    CalibrationTask,
    calibration_specs,
    calibration_table,
    pairs,
    play,
)

SMALL = (("objects_per_scene", 8), ("pool_size", 24), ("test_size", 16))


@pytest.fixture(scope="module")
def episode():
    spec = calibration_specs(["dt-task"], 101, 1, [41], turns=8, plan=SMALL)[0]
    return play(CalibrationTask(spec)), play(CalibrationTask(spec, record=False))


def test_the_recorder_changes_no_decision(episode):
    recorded, plain = episode
    assert recorded["actions"] == plain["actions"] and recorded["accuracy"] == plain["accuracy"]
    assert plain["records"] == []


def test_every_record_is_consistent_with_the_states_before_and_after(episode):
    recorded, _ = episode
    records = recorded["records"]
    assert records and len(records) + recorded["quiet_turns"] == len(recorded["actions"]) == 8
    asked = [a["kind"] for a in recorded["actions"] if a["kind"] != "none"]
    assert [r["kind"] for r in records] == asked and all(r["kind"] in KINDS for r in records)
    for r in records:
        before, after = np.array(r["phi_before"]), np.array(r["phi_after"])
        np.testing.assert_allclose(r["realised"], after - before, atol=1e-12)
        np.testing.assert_allclose(r["phi_seen"], before, atol=1e-9)  # the strategy's phi(s) is the state's
        np.testing.assert_allclose(r["predicted"], np.array(r["expected_after"]) - np.array(r["phi_seen"]),
                                   atol=1e-12)
        assert r["realised_accuracy_end"] == pytest.approx(recorded["accuracy"] - r["accuracy_before"])
        assert -1 <= r["predicted_accuracy"] <= 1 and -1 <= r["realised_accuracy_turn"] <= 1
    assert [r["turn"] for r in records] == sorted({r["turn"] for r in records})


def test_the_table_is_the_records_means(episode):
    records = episode[0]["records"]
    table = calibration_table(records)
    for row in table:
        p, q = pairs([r for r in records if r["kind"] == row["kind"]], row["target"])
        assert row["n"] == len(p) and row["predicted"] == pytest.approx(p.mean())
        assert row["realised"] == pytest.approx(q.mean()) and row["mae"] == pytest.approx(np.abs(p - q).mean())
