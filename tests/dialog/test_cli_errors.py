"""The command line prints bad input as one line and lets a real bug show its traceback."""

from __future__ import annotations

import numpy as np
import pytest

import dialog.commands.demo
from bullet_world.kitchen import load_kitchen
from bullet_world.placement import Footprint, PlacementError, place
from dialog.cli import main
from dialog.manager import EpisodeConfig
from learning.errors import (
    DataFileError,
    OutputPathError,
    SceneError,
    SettingsError,
    SetupError,
    TeachbotError,
    TranscriptError,
)

BAD_INPUT = (DataFileError, OutputPathError, TranscriptError, SettingsError, SceneError, SetupError, PlacementError)


def _handler_raising(error: BaseException):
    def handler(args):
        raise error
    return handler


@pytest.mark.parametrize("bug", [ValueError("a plain bug"), KeyError("missing key"), RuntimeError("broken"),
                                 FileNotFoundError("internal file"), TypeError("wrong call")])
def test_a_bug_in_a_handler_keeps_its_traceback(monkeypatch, bug):
    monkeypatch.setattr(dialog.commands.demo, "run", _handler_raising(bug))
    with pytest.raises(type(bug)) as raised:
        main(["demo"])
    assert raised.value is bug


@pytest.mark.parametrize("kind", BAD_INPUT)
def test_bad_input_of_every_kind_is_one_line_and_exit_2(monkeypatch, capsys, kind):
    monkeypatch.setattr(dialog.commands.demo, "run", _handler_raising(kind("--thing 7: accepted are 1 to 3")))
    assert main(["demo"]) == 2
    err = capsys.readouterr().err
    assert err == "teachbot demo: --thing 7: accepted are 1 to 3\n"


@pytest.mark.parametrize("kind", BAD_INPUT)
def test_bad_input_errors_stay_value_errors_for_library_users(kind):
    assert issubclass(kind, TeachbotError) and issubclass(kind, ValueError)


def test_scene_and_setup_errors_are_still_runtime_errors():
    """Placement failures and missing extras were RuntimeErrors; callers catching that still catch them."""
    assert issubclass(SceneError, RuntimeError) and issubclass(PlacementError, RuntimeError)
    assert issubclass(SetupError, RuntimeError)


@pytest.mark.parametrize(("settings", "option"), [({"turns": 0}, "turns"), ({"budget": -1}, "budget"),
                                                  ({"change_every": 0}, "change-every"), ({"realtime": 0}, "realtime")])
def test_episode_settings_refuse_bad_values_naming_the_option(settings, option):
    with pytest.raises(SettingsError, match=option):
        EpisodeConfig(**settings)


def test_a_missing_replay_transcript_is_one_line(tmp_path, capsys):
    missing = tmp_path / "missing.jsonl"
    code = main(["teach", "--teacher", "replay", "--replay", str(missing), "--transcript", str(tmp_path / "t.jsonl"),
                 "--no-pictures", "--turns", "1"])
    assert code == 2
    assert capsys.readouterr().err == f"teachbot teach: {missing}: no such transcript; give a transcript file that " \
                                      "teachbot wrote\n"


def test_a_missing_resume_transcript_is_one_line(tmp_path, capsys):
    missing = tmp_path / "gone.jsonl"
    assert main(["teach", "--resume", str(missing)]) == 2
    assert capsys.readouterr().err == f"teachbot teach: no transcript at {missing} to resume\n"


def test_too_many_objects_for_the_kitchen_is_a_scene_error():
    with pytest.raises(SceneError, match="cannot place 200 objects"):
        place([Footprint("rect", 0.1, 0.05)] * 200, load_kitchen("kitchen-1"), np.random.default_rng(0))


@pytest.mark.parametrize("arguments, hint", [
    (["demo", "--strategy", "dt-tsk"], "(did you mean 'dt-task'?)"),
    (["demo", "--task", "pack-lunchbx"], "(did you mean 'pack-lunchbox'?)"),
    (["demo", "--kitchen", "kitchn-2"], "(did you mean 'kitchen-2'?)"),
    (["regress", "--suite", "smok"], "(did you mean 'smoke'?)"),
])
def test_an_unknown_name_close_to_a_known_one_says_which(arguments, hint, capsys):
    try:
        code = main(arguments)
    except SystemExit as stop:  # argparse's own refusal of an option value
        code = stop.code
    assert code == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert error.startswith("teachbot") and hint in error


def test_a_name_close_to_nothing_gets_no_hint():
    from learning.errors import did_you_mean
    assert did_you_mean("xyzzy", ["smoke", "ch7"]) == ""
