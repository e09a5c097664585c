"""Embodied query costs in the dialog (thesis §8.2.2): the motion-time model, seconds allocations, the CLI."""

from __future__ import annotations

import numpy as np
import pytest

from dialog.cli import main
from dialog.clock import VirtualClock
from dialog.embodied import (
    BEARING,
    DISTANCE,
    load_embodied_costs,
    load_pointing_model,
)
from dialog.manager import DialogManager, EpisodeConfig, episode_generators
from dialog.teachers.scripted import ScriptedTeacher
from dialog.transcripts.jsonl import TranscriptWriter, read_session, read_transcript
from learning.errors import DataFileError, SettingsError
from learning.strategies import make_strategy
from tests.dialog.fakes import FakeEnvironment, QuittingTeacher


class RoomEnvironment(FakeEnvironment):
    """The fake world with the two measured features embodied costs need (distance and bearing to the robot)."""

    feature_names = ("f1", DISTANCE, BEARING)


def test_the_motion_model_loads_and_a_farther_object_never_takes_less():
    costs = load_embodied_costs()
    model = costs.pointing
    distances = np.linspace(0.2, 1.0, 41)
    for bearing in (-1.4, -0.5, 0.0, 0.7, 1.4):
        seconds = model.seconds(distances, np.full_like(distances, bearing))
        assert np.all(np.diff(seconds) >= 0) and np.all(seconds > 0)
    low, high = model.distance_range
    assert model.seconds([high], [0.0])[0] > model.seconds([low], [0.0])[0]  # far costs more than near
    assert costs.turn_seconds()["label"] > 0 and costs.quiet > 0 and costs.fetch > 0


def test_a_model_measured_at_another_joint_speed_is_refused(tmp_path):
    from dialog.embodied import COSTS_FILE, POINTING_FILE

    other = tmp_path / "pointing.toml"
    other.write_text(POINTING_FILE.read_text().replace("joint_speed = 1\n", "joint_speed = 2\n"))
    assert load_pointing_model(other)[0].joint_speed == 2
    with pytest.raises(DataFileError, match="refit it"):
        load_embodied_costs.__wrapped__(COSTS_FILE, other)
    broken = tmp_path / "broken.toml"
    broken.write_text(POINTING_FILE.read_text().replace('terms = ["1"', 'terms = ["cube"'))
    with pytest.raises(DataFileError, match="unknown terms"):
        load_pointing_model(broken)


def embodied_run(tmp_path, name="t.jsonl", seconds=120.0, turns=200, strategy="dt-task", quit_at=None,
                 resume_from=None):
    config = EpisodeConfig(turns=turns, budget=40, change_every=3, seed=2, seconds=seconds)
    rngs = episode_generators(config.seed)
    clock = VirtualClock()
    inner = ScriptedTeacher(rngs["teacher"], clock=clock, answer_delays=load_embodied_costs().answer)

    path, records = tmp_path / name, []
    if resume_from is not None:
        path, records = resume_from, read_session(resume_from, tolerate_partial_tail=True)[1]
    writer = TranscriptWriter(path, append=resume_from is not None)
    teacher = QuittingTeacher(inner, quit_at)
    manager = DialogManager(RoomEnvironment(), teacher, make_strategy(strategy), config, writer, rngs,
                            say=lambda _: None, clock=clock)
    result = manager.run(replay=records)
    writer.close()
    return result, path, manager


def test_an_embodied_episode_ends_when_its_seconds_are_used_up(tmp_path):
    result, path, manager = embodied_run(tmp_path)
    header, records = read_session(path)
    assert header["seconds"] == 120.0 and "embodied_costs" in header
    assert result.completed == len(records) < 200  # the seconds ended it, not the turns cap
    assert records[-1]["ended"] >= 120.0 > records[-2]["ended"]
    for record in records:
        assert record["seconds"] == pytest.approx(record["ended"] - record["time"], abs=2e-3) and record["seconds"] > 0
    costs = load_embodied_costs()
    for record in records:
        kind = record["action"]["kind"]
        if kind == "none":
            assert record["seconds"] == pytest.approx(costs.quiet)
        else:  # saying it, the answer, and for a label the modelled pointing (no arm in this world)
            assert record["seconds"] > costs.speaking[kind]
        if kind == "label":
            assert record["gesture"]["model_seconds"] > 0
    assert any("the most per second it takes" in r["explanation"] for r in records)


def test_the_turns_cap_still_ends_an_embodied_episode(tmp_path):
    result, path, _ = embodied_run(tmp_path, turns=4)
    assert result.completed == 4 and read_transcript(path)[-1]["ended"] < 120.0


def test_an_embodied_session_resumes_to_the_same_transcript(tmp_path):
    _, whole, _ = embodied_run(tmp_path, "whole.jsonl")
    result, broken, _ = embodied_run(tmp_path, "broken.jsonl", quit_at=5)
    assert result.quit
    resumed, _, manager = embodied_run(tmp_path, "unused", resume_from=broken)
    assert not resumed.quit and manager.clock.now() >= 120.0
    assert broken.read_bytes() == whole.read_bytes()


def test_dt_in_turns_ignores_the_seconds(tmp_path):
    strategy = make_strategy("dt-task+turns")
    assert strategy.name == "dt-task+turns" and strategy.embodied is False
    with pytest.raises(SettingsError, match="only a DT strategy"):
        make_strategy("active+turns")
    _, path, _ = embodied_run(tmp_path, strategy="dt-task+turns")
    assert not any("the most per second it takes" in r["explanation"] for r in read_transcript(path))


@pytest.mark.parametrize("argv, expected", [
    (["demo", "--time", "ten"], "'ten' is not a number of turns (e.g. --time 40) or of seconds ending in s"),
    (["demo", "--time", "0s"], "seconds must be a positive number"),
    (["demo", "--time", "-3"], "turns must be at least 1"),
    (["teach", "--time", "1.5"], "is not a number of turns"),
    (["demo", "--time", "600s"], "a time in seconds needs --embodied-costs"),
    (["demo", "--time", "20", "--turns", "25"], "both give the time allocation; give one"),
    (["regress", "--suite", "smoke", "--embodied-costs", "--check"], "the stored baseline, which was made in turns"),
])
def test_bad_time_values_are_refused_in_one_line(argv, expected, capsys):
    try:
        code = main(argv)
    except SystemExit as exit_:
        code = exit_.code
    err = capsys.readouterr().err
    assert code == 2 and expected in err and err.count("\n") == 1, err


def test_a_persons_clock_with_embodied_costs_counts_the_arms_simulated_seconds():
    from dialog.clock import WallClock

    now = [100.0]
    plain, embodied = WallClock(monotonic=lambda: now[0]), WallClock(monotonic=lambda: now[0], counts_simulated=True)
    now[0] += 5.0
    plain.advance(3.0)
    embodied.advance(3.0)
    assert plain.now() == pytest.approx(5.0) and embodied.now() == pytest.approx(8.0)


def test_pointing_from_the_last_object_depends_on_how_far_it_is_from_there():
    costs = load_embodied_costs()
    X = np.array([[0.0, 0.50, 0.0], [0.0, 0.52, 0.05], [0.0, 0.75, 1.2]])
    rest = costs.pointing_seconds(X, RoomEnvironment.feature_names)
    onward = costs.pointing_seconds(X, RoomEnvironment.feature_names, last=0)
    assert onward[1] < onward[2] and onward[1] < rest[1]


def test_the_learner_expects_pointing_from_where_the_arm_is():
    from learning.actions import LabelQuery, NoQuery
    from tests.dialog.fakes import ScriptedStrategy

    config = EpisodeConfig(turns=20, budget=40, change_every=2, seed=2, seconds=600.0)
    rngs = episode_generators(config.seed)
    clock = VirtualClock()
    costs = load_embodied_costs()
    strategy = ScriptedStrategy([LabelQuery(2)] + [NoQuery()] * 19)
    with TranscriptWriter(tmp_path_factory_dir() / "t.jsonl") as writer:
        manager = DialogManager(RoomEnvironment(), ScriptedTeacher(rngs["teacher"], clock=clock), strategy, config,
                                writer, rngs, say=lambda _: None, clock=clock)
        manager.begin()
        manager.play_turn()
        scene = manager.scene
        manager.play_turn()  # same scene: the arm still points at object 3
        np.testing.assert_allclose(manager.state.seconds_clock.pointing,
                                   costs.pointing_seconds(scene.X, scene.feature_names, last=2))
        while manager.scene is scene:  # quiet 2 s turns until the next scene (every 2 nominal turns of 10 s)
            manager.play_turn()
        np.testing.assert_allclose(manager.state.seconds_clock.pointing,
                                   costs.pointing_seconds(manager.scene.X, manager.scene.feature_names))


def tmp_path_factory_dir():
    import tempfile
    from pathlib import Path

    return Path(tempfile.mkdtemp())
