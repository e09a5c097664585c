"""train-questioner says what it does before its slow steps and counts the episodes it averages (issue 42, case 4)."""

from __future__ import annotations

from pathlib import Path

import pytest

from dialog.commands.train_questioner import final_accuracy_words, trained_words


def test_the_final_accuracy_names_the_episodes_it_averages():
    assert final_accuracy_words({"episodes": 8, "final_accuracy_episodes": 8, "final_accuracy_last_50": 0.585}) == \
        "final accuracy of all 8 training episodes 0.585"
    assert final_accuracy_words({"episodes": 80, "final_accuracy_episodes": 50, "final_accuracy_last_50": 0.7}) == \
        "final accuracy of the last 50 training episodes 0.700"
    assert final_accuracy_words({"episodes": 1, "final_accuracy_episodes": 1, "final_accuracy_last_50": 0.5}) == \
        "final accuracy of the one training episode 0.500"
    assert "no training episode ended" in final_accuracy_words(
        {"episodes": 0, "final_accuracy_episodes": 0, "final_accuracy_last_50": None})


def test_the_last_line_names_both_files_with_their_folder():
    """Issue 51: ``--out DIR/small.toml`` said "wrote DIR/small.toml and small.npz", the npz being in DIR too."""
    summary = {"steps": 256, "episodes": 32, "seconds": 79.2, "estimated_seconds": 80.0, "final_accuracy_episodes": 32,
               "final_accuracy_last_50": 0.424}
    assert trained_words(summary, Path("runs/rl/small.toml")) == (
        "256 steps, 32 episodes in 79 s (estimated 80 s); final accuracy of all 32 training episodes 0.424; "
        "wrote runs/rl/small.toml and runs/rl/small.npz")


def test_training_says_it_loads_the_data_sets_before_it_does(monkeypatch):
    pytest.importorskip("sb3_contrib")
    from dialog.rl import training

    said = []

    class Loading(Exception):
        pass

    def make_env(options):
        def build():
            raise Loading(list(said))
        return build

    monkeypatch.setattr(training, "make_env", make_env)
    with pytest.raises(Loading) as loading:
        training.train(training.TrainingConfig(steps=64, envs=1), progress=False, say=said.append)
    assert loading.value.args[0] == ["loading the training data sets (rendered in the simulated kitchen on the "
                                     "first run, then cached)..."]
