"""The command line's own voice: descriptions on every subcommand, accepted names listed, errors in one line."""

from __future__ import annotations

import argparse

import pytest

from bullet_world.datafiles import available
from dialog.cli import build_parser, main
from dialog.commands._arguments import kitchen_name, task_name
from dialog.commands._summary import questions_in_words


def _subparsers(parser: argparse.ArgumentParser, path=("teachbot",)):
    """Every (command path, parser) below ``parser``, depth first."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*path, name), sub
                yield from _subparsers(sub, (*path, name))


ALL_PARSERS = list(_subparsers(build_parser()))


def test_the_walk_finds_every_command():
    names = {" ".join(path) for path, _ in ALL_PARSERS}
    assert {"teachbot demo", "teachbot view", "teachbot recipe", "teachbot regress", "teachbot teach",
            "teachbot expert", "teachbot learn-weights", "teachbot world", "teachbot world show",
            "teachbot world check", "teachbot world data"} <= names


@pytest.mark.parametrize("path, parser", ALL_PARSERS, ids=[" ".join(p) for p, _ in ALL_PARSERS])
def test_every_subcommand_has_a_description(path, parser):
    assert parser.description and len(parser.description) > 40, f"{' '.join(path)} has no description"
    assert " ".join(parser.description.split()[:6]) in " ".join(parser.format_help().split())


@pytest.mark.parametrize("path, parser", ALL_PARSERS, ids=[" ".join(p) for p, _ in ALL_PARSERS])
def test_task_and_kitchen_options_list_the_names_of_the_data_files(path, parser):
    help_text = " ".join(parser.format_help().split())
    for option in parser._actions:
        if "--task" in option.option_strings:
            assert all(name in help_text for name in available("tasks")), " ".join(path)
            assert option.type is task_name
        if "--kitchen" in option.option_strings:
            assert all(name in help_text for name in available("kitchens")), " ".join(path)
            assert option.type is kitchen_name


def test_a_kitchen_is_accepted_by_number_or_name_everywhere():
    parser = build_parser()
    for argv in (["demo"], ["teach"], ["view"], ["world", "show"], ["world", "data"], ["expert"], ["recipe"]):
        assert parser.parse_args([*argv, "--kitchen", "2"]).kitchen == "kitchen-2"
        assert parser.parse_args([*argv, "--kitchen", "kitchen-3"]).kitchen == "kitchen-3"
    assert parser.parse_args(["world", "check", "--kitchen", "1", "--kitchen", "kitchen-2"]).kitchen == [
        "kitchen-1", "kitchen-2"]


def _refusal(capsys, *argv) -> str:
    with pytest.raises(SystemExit) as raised:
        main(list(argv))
    assert raised.value.code == 2
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and "usage:" not in captured.err
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    return lines[0]


def test_a_bad_seed_is_refused_in_the_tools_own_voice(capsys):
    assert _refusal(capsys, "regress", "--suite", "smoke", "--seeds", "a") == (
        "teachbot regress: --seeds: 'a' is not a whole number (give one or more seeds, e.g. --seeds 0 1 2)")
    assert _refusal(capsys, "demo", "--seed", "1.5").startswith("teachbot demo: --seed: '1.5' is not a whole number")
    assert "is negative" in _refusal(capsys, "world", "show", "--seed", "-2")


def test_unknown_names_are_refused_with_the_accepted_ones(capsys):
    kitchen = _refusal(capsys, "demo", "--kitchen", "9")
    assert kitchen.startswith("teachbot demo: --kitchen: no kitchen '9'; accepted: kitchen-1, kitchen-2, kitchen-3")
    task = _refusal(capsys, "view", "--task", "pack-lunch")
    assert task.startswith("teachbot view: --task: no task 'pack-lunch' (did you mean 'pack-lunchbox'?); accepted: ")
    assert all(name in task for name in available("tasks"))
    strategy = _refusal(capsys, "demo", "--strategy", "clever")
    assert strategy.startswith("teachbot demo: --strategy: 'clever' is not one of the accepted names: ")
    assert "dt-task" in strategy and "invalid choice" not in strategy


@pytest.mark.parametrize("argv, expected", [
    (["regress"], "teachbot regress: --suite must be given (see teachbot regress --help)"),
    (["world"], "teachbot world: ACTION must be given (see teachbot world --help)"),
    (["demo", "--turns"], "teachbot demo: --turns: needs a value"),
    (["demo", "--turns", "x"], "teachbot demo: --turns: expected a whole number, got 'x'"),
    (["nonsense"], "teachbot: COMMAND: 'nonsense' is not one of the accepted names: "),
])
def test_every_argparse_error_is_one_line_in_the_tools_voice(capsys, argv, expected):
    assert _refusal(capsys, *argv).startswith(expected)


def test_demo_defaults_to_dt_task():
    assert build_parser().parse_args(["demo"]).strategy == "dt-task"


def test_questions_are_counted_in_words():
    assert questions_in_words({"label": 6, "demo": 3, "feature": 1, "none": 20}) == (
        "6 labels, 3 demonstrations, 1 feature question, 20 quiet turns")
    assert questions_in_words({"label": 1, "demo": 0, "feature": 0, "none": 1}) == (
        "1 label, 0 demonstrations, 0 feature questions, 1 quiet turn")
    with pytest.raises(ValueError, match="unknown query kinds"):
        questions_in_words({"label": 1, "shout": 2})


def test_session_time_counts_the_recorded_part_of_a_resumed_session():
    from dialog.clock import VirtualClock, WallClock
    from dialog.commands._summary import session_time

    now = [50.0]
    clock = WallClock(start=100.0, monotonic=lambda: now[0])  # the clock goes on from the transcript's end
    now[0] += 12.5
    assert session_time(clock, 3.0, [{"turn": 1, "ended": 100.0}]) == (
        "112.5 s in all (100.0 s before the resume, 12.5 s after)")
    assert session_time(WallClock(monotonic=lambda: 7.0), 7.0, []) == "0.0 s"
    assert session_time(VirtualClock(30.0), 2.25, []) == "2.2 s"
    assert session_time(VirtualClock(30.0), 2.25, [{}, {}]) == "2.2 s in this run (2 recorded turns replayed)"
