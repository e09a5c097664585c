"""`teachbot learn-weights` on the shipped scripted-expert demonstrations; bad input; the shipped learned file."""

import json

import numpy as np
import pytest

from dialog.cli import main
from learning.decision.features import FEATURE_NAMES
from learning.decision.weights import WEIGHTS_DIRECTORY, load_weight_file
from learning.decision.weights_file import load_weights

LEARNED = WEIGHTS_DIRECTORY / "dt-task-env-v1.toml"  # issue 27's learned weights (dt-task-env-v1)


def test_learn_weights_per_turn_on_the_shipped_demos_prints_the_summary(tmp_path, capsys):
    """The per-turn fit (--method per-turn) on the shipped demonstrations, which record the eleven features."""
    from learning.decision.habits import EXTENDED_FEATURE_NAMES

    out = tmp_path / "w.toml"
    assert main(["learn-weights", "--demos", "shipped", "--out", str(out), "--method", "per-turn", "--no-check",
                 "--json"]) == 0
    captured = capsys.readouterr()
    assert "cannot identify remaining_time" in captured.err  # named, and left at 0
    summary = json.loads(captured.out.strip().splitlines()[-1])
    assert set(summary) == {"iterations", "seconds", "weights", "validation_agreement", "ship_rule", "rollout_check"}
    assert summary["ship_rule"]["passes"] is None and summary["rollout_check"] is None  # --no-check: not judged
    assert 0.0 <= summary["validation_agreement"] <= 1.0 and 1 <= summary["iterations"] <= 100
    assert list(summary["weights"]) == list(EXTENDED_FEATURE_NAMES) and summary["weights"]["remaining_time"] == 0.0
    np.testing.assert_array_equal(load_weight_file(out), [summary["weights"][n] for n in EXTENDED_FEATURE_NAMES])


def test_a_fit_that_can_never_ask_is_refused_unless_allowed(tmp_path, capsys):
    """Issue 23 case 2 / issue 27 item 2: the seven features alone on demonstrations whose asks they cannot tell
    apart give all-zero weights with a zero start; --allow-degenerate writes them, with a warning."""
    demos = tmp_path / "demos"
    demos.mkdir()
    from learning.irl.demonstrations import DecisionTurn, QuestioningEpisode, save_episodes

    phi = np.zeros((3, len(FEATURE_NAMES)))
    turns = tuple(DecisionTurn(phi, t % 3, ("label", "label", "none")) for t in range(6))
    for i in range(3):
        save_episodes(demos / f"flat{i}.json", [QuestioningEpisode(FEATURE_NAMES, turns, f"flat{i}", {})])
    out = tmp_path / "w.toml"
    assert main(["learn-weights", "--demos", str(demos), "--out", str(out), "--method", "per-turn"]) == 2
    error = capsys.readouterr().err
    assert "nothing written" in error and "can never ask" in error and "--allow-degenerate" in error
    assert not out.exists()
    assert main(["learn-weights", "--demos", str(demos), "--out", str(out), "--method", "per-turn",
                 "--allow-degenerate", "--no-check"]) == 0
    assert sum("never asks" in line for line in capsys.readouterr().err.splitlines()) == 1 and out.exists()


def test_the_shipped_learned_weights_say_where_they_came_from():
    from learning.decision.habits import EXTENDED_FEATURE_NAMES

    provenance = load_weights(LEARNED, EXTENDED_FEATURE_NAMES).provenance
    assert provenance["method"] == "maxent-irl-per-turn-imitation" and provenance["demos"] == "shipped"
    assert {"commit", "data_seed", "split_seeds", "fit_seeds", "kept_split_seed", "kept_fit_seed",
            "held_out_exact_agreement", "validation_log_likelihood", "ship_rule"} <= set(provenance)
    assert len(provenance["held_out_episodes"].split(", ")) == 10


def test_bad_demonstrations_get_one_clear_message(tmp_path, capsys):
    assert main(["learn-weights", "--demos", str(tmp_path / "missing"), "--out", str(tmp_path / "w.toml")]) == 2
    assert "no such file or directory" in capsys.readouterr().err
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "broken.json").write_text('{"format": "teachbot-irl-demonstrations", "version": 1, "episodes": 3}')
    assert main(["learn-weights", "--demos", str(bad), "--out", str(tmp_path / "w.toml")]) == 2
    error = capsys.readouterr().err
    assert "broken.json" in error and len(error.strip().splitlines()) == 1
    assert main(["learn-weights", "--demos", "shipped", "--out", str(tmp_path / "w.txt")]) == 2
    assert "must end in .toml" in capsys.readouterr().err


def test_learning_weights_without_validation_episodes_is_refused_before_fitting():
    """The kept iterate is the best on validation; with none held out the provenance had no agreement to round."""
    from learning.errors import SettingsError
    from learning.irl.learn import learn_weights

    with pytest.raises(SettingsError, match=r"n_validation must be at least 1 \(.*\), got 0"):
        learn_weights("shipped", n_validation=0)


@pytest.mark.parametrize("value", ["1e308", "-2e6"])
def test_a_weight_beyond_the_stated_magnitude_is_refused_naming_the_file(tmp_path, capsys, value):
    """Issue 24: DT weights of 1e308 ran; a weight must be finite and within learning/data/limits.toml's limit."""
    from learning.errors import DataFileError

    path = tmp_path / "w.toml"
    path.write_text(f"[weights]\n{FEATURE_NAMES[0]} = {value}\n")
    with pytest.raises(DataFileError, match=rf"{path}: weight '{FEATURE_NAMES[0]}' .*beyond the limit of 1e\+06"):
        load_weights(path)
    with pytest.raises(ValueError, match="beyond the limit of 1e"):
        from learning.decision.weights import weight_vector

        weight_vector({FEATURE_NAMES[0]: float(value)})
    assert main(["demo", "--turns", "1", "--weights", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "beyond the limit" in err[0], err
