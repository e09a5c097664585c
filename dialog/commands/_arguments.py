"""Argument types and option groups shared by several subcommands."""

from __future__ import annotations

import argparse
import re
import sys
import textwrap
from pathlib import Path

from bullet_world.datafiles import available
from dialog.printed_command import command_line
from dialog.settings import DEFAULTS, EpisodeSettings
from learning.errors import SettingsError, did_you_mean
from learning.strategies import PLUGIN_FORM, RL_PREFIX, check_strategy_name, is_plugin_spec


class HelpFormatter(argparse.HelpFormatter):
    """argparse's help, but a name such as ``sort-groceries`` is never split across lines at its hyphen."""

    def _split_lines(self, text, width):
        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)

    def _fill_text(self, text, width, indent):
        return textwrap.fill(" ".join(text.split()), width, initial_indent=indent, subsequent_indent=indent,
                             break_on_hyphens=False)


class TeachbotParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line in the tool's voice: ``teachbot demo: --seed: ...``, exit 2."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
        self._arguments: list[str] = []

    def parse_known_args(self, args=None, namespace=None):
        self._arguments = list(sys.argv[1:] if args is None else args)  # for a value that looks like an option
        return super().parse_known_args(args, namespace)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: {self._dash_value(message) or own_voice(message, self.prog)}\n")

    def _dash_value(self, message: str) -> str | None:
        """``--time -5s``: argparse takes ``-5s`` for an option and says "expected one argument"; say what is
        wrong with the value instead (its type's message), or how to give a value that starts with '-'."""
        named = re.fullmatch(r"argument (\S+?)(?:/(\S+))?: expected one argument", message)
        if not named:
            return None
        options = [o for o in (named.group(1), named.group(2)) if o]
        spots = [i for i, word in enumerate(self._arguments) if word in options]
        if not spots or spots[-1] + 1 >= len(self._arguments):
            return None
        option, value = self._arguments[spots[-1]], self._arguments[spots[-1] + 1]
        action = self._option_string_actions.get(option)
        if not value.startswith("-") or action is None:
            return None
        try:
            if callable(action.type):
                action.type(value)
        except (argparse.ArgumentTypeError, ValueError, TypeError) as error:
            return own_voice(f"argument {option}: invalid {getattr(action.type, '__name__', 'value')} value: "
                             f"'{value}'", self.prog) if not str(error) else f"{option}: {error}"
        return f"{option}: '{value}' starts with '-' and reads as an option; write {option}={value}"


def own_voice(message: str, prog: str) -> str:
    """argparse's wording (``argument --x: invalid choice: ...``) said the way the rest of the tool says things."""
    choice = re.fullmatch(r"argument (\S+): invalid choice: '(.*)' \(choose from (.*)\)", message, re.S)
    if choice:
        accepted = ", ".join(name.strip().strip("'") for name in choice.group(3).split(","))
        return f"{choice.group(1)}: '{choice.group(2)}' is not one of the accepted names: {accepted}"
    value = re.fullmatch(r"argument (\S+): invalid (\w+) value: '(.*)'", message, re.S)
    if value:
        what = {"int": "a whole number", "float": "a number"}.get(value.group(2), f"a valid {value.group(2)}")
        return f"{value.group(1)}: '{value.group(3)}' is not {what}"
    required = re.fullmatch(r"the following arguments are required: (.*)", message, re.S)
    if required:
        return f"{required.group(1)} must be given (see {_help_command(prog)})"
    unknown = re.fullmatch(r"unrecognized arguments: (.*)", message, re.S)
    if unknown:
        return f"unknown argument(s) {unknown.group(1)} (see {_help_command(prog)} for the accepted ones)"
    named = re.fullmatch(r"argument (\S+?)(?:/\S+)?: (.*)", message, re.S)
    if named:
        problem = "needs a value" if named.group(2) == "expected one argument" else named.group(2)
        return f"{named.group(1)}: {problem}"
    return message


def _help_command(prog: str) -> str:
    """``teachbot regress --help`` for argparse's ``prog`` "teachbot regress", runnable as printed."""
    return command_line([*prog.split()[1:], "--help"])


ASCII_WHOLE = re.compile(r"[+-]?[0-9]+")
ASCII_NUMBER = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?")


def _read_number(text: str, kind):
    """``text`` as ``kind`` (int or float) written with ASCII digits only: Python's int() and float() also take
    '٣' (an Arabic-Indic 3) and '1_0' (10), which a command line must not read as numbers."""
    pattern = ASCII_WHOLE if kind is int else ASCII_NUMBER
    if not pattern.fullmatch(text.strip()):
        if kind is float and text.strip().lower().lstrip("+-") in ("inf", "infinity", "nan"):
            return float(text)
        raise ValueError(text)
    return kind(text)


def _ascii_hint(text: str, kind) -> str:
    """What to say when Python would have read ``text`` as a number the command line refuses ('٣', '1_0')."""
    try:
        kind(text)
    except ValueError:
        return ""
    return "; write numbers in ASCII digits 0-9, without '_'"


def _number(text: str, kind, what: str):
    """``text`` read as ``kind`` (int or float), finite; argparse's error names what was expected."""
    try:
        value = _read_number(text, kind)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got '{text}'{_ascii_hint(text, kind)}") from None
    if kind is float and value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"expected {what}, got '{text}', which is not a finite number")
    return value


def _at_least(kind, what: str, minimum: float, too_small: str):
    """An argparse type: a finite ``kind`` number of at least ``minimum`` (``too_small`` says why not)."""
    def parse(text: str):
        value = _number(text, kind, what)
        if value < minimum:
            raise argparse.ArgumentTypeError(too_small.format(value=value))
        return value
    return parse


def _whole_number(example: str):
    """An argparse type: a whole number of 0 or more in ASCII digits; the error gives ``example`` of what to write."""
    def parse(text: str) -> int:
        try:
            value = _read_number(text, int)
        except ValueError:
            raise argparse.ArgumentTypeError(f"'{text}' is not a whole number ({example}){_ascii_hint(text, int)}") \
                from None
        if value < 0:
            raise argparse.ArgumentTypeError(f"'{text}' is negative ({example})")
        return value
    return parse


def number_within(kind, low: float, high: float, what: str):
    """An argparse type: a ``kind`` number (int or float, ASCII digits) from ``low`` to ``high``; ``what`` says
    what is expected, e.g. "a number between 0 and 1"."""
    def parse(text: str):
        value = _number(text, kind, what)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {what}, got {value:g}")
        return value
    return parse


seed = _whole_number("give a seed of 0 or more, e.g. --seed 0")
seeds = _whole_number("give one or more seeds, e.g. --seeds 0 1 2")
data_seed = _whole_number("give the seed the data sets are rendered from, 0 or more, e.g. --data-seed 1")
stage = _whole_number("give a state stage of 0 or more, e.g. --stage 1")


def task_names() -> list[str]:
    """The tasks in ``bullet_world/data/tasks``."""
    return available("tasks")


def kitchen_names() -> list[str]:
    """The kitchens in ``bullet_world/data/kitchens``."""
    return available("kitchens")


def task_name(text: str) -> str:
    """A task data file's name, or a path to a task .toml file."""
    if text.endswith(".toml") or text in task_names():
        return text
    raise argparse.ArgumentTypeError(f"no task '{text}'{did_you_mean(text, task_names())}; accepted: "
                                     f"{', '.join(task_names())} (or a task .toml file)")


def kitchen_name(text: str) -> str:
    """A kitchen's name, or its number (``1`` -> ``kitchen-1``), or a path to a kitchen .toml file."""
    name = f"kitchen-{text}" if text.isdigit() else text
    if name.endswith(".toml") or name in kitchen_names():
        return name
    numbers = ", ".join(name.removeprefix("kitchen-") for name in kitchen_names())
    raise argparse.ArgumentTypeError(f"no kitchen '{text}'{did_you_mean(text, kitchen_names())}; accepted: "
                                     f"{', '.join(kitchen_names())} (or just the "
                                     f"number: {numbers}; or a kitchen .toml file)")


def add_task_option(parser: argparse.ArgumentParser, default: str | None, help_default: str | None = None) -> None:
    """``--task NAME``, the accepted names listed in --help."""
    parser.add_argument("--task", default=default, type=task_name, metavar="TASK",
                        help=f"task: {', '.join(task_names())} or a .toml file (default {help_default or default}); "
                             "scenes hold the task's interactive number of objects (pack-lunchbox: 12, where the "
                             "thesis's experiments and regress's ch6-static and ch7-pack-lunchbox use 55)")


def add_kitchen_option(parser: argparse.ArgumentParser, default: str | None, default_text: str | None = None,
                       **extra) -> None:
    """``--kitchen NAME`` (or its number), the accepted names listed in --help; ``extra`` goes to add_argument."""
    numbers = ", ".join(name.removeprefix("kitchen-") for name in kitchen_names())
    parser.add_argument("--kitchen", default=default, type=kitchen_name, metavar="KITCHEN",
                        help=f"kitchen: {', '.join(kitchen_names())}, or just its number ({numbers}), or a "
                             f"kitchen .toml file (teachbot world generate writes them) "
                             f"(default {default_text or default})", **extra)


def add_scene_options(parser: argparse.ArgumentParser) -> None:
    """``--task``, ``--kitchen`` and ``--seed`` of one scene, as demo's first scene (view, world show)."""
    add_task_option(parser, "pack-lunchbox")
    add_kitchen_option(parser, "kitchen-1")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the scene (default 0)")


positive_int = _at_least(int, "a whole number", 1, "expected a whole number of at least 1, got {value}")
budget = _at_least(float, "a number of cost units", 0, "the budget can't be negative, got {value:g}")
price = _at_least(float, "a number", 0, "the price can't be negative, got {value:g}")
seconds = _at_least(float, "a number of seconds", 0, "expected zero or more seconds, got {value:g}")


def positive_seconds(text: str) -> float:
    value = seconds(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {value:g}")
    return value


def strategy_choice(strategies):
    """An argparse type: one of ``strategies``, ``rl:FILE`` (the file made absolute, so a resume finds it) or
    ``module.path:ClassName`` (imported now, so a bad one is one message before anything runs)."""
    def parse(text: str) -> str:
        if text.startswith(RL_PREFIX) and len(text) > len(RL_PREFIX):
            return RL_PREFIX + str(Path(text[len(RL_PREFIX):]).resolve())
        if is_plugin_spec(text):
            try:
                return check_strategy_name(text)
            except SettingsError as error:
                raise argparse.ArgumentTypeError(str(error)) from None
        if text in strategies:
            return text
        raise argparse.ArgumentTypeError(f"'{text}'{did_you_mean(text, strategies)} is not one of the accepted names: "
                                         f"{', '.join(strategies)}, "
                                         f"rl:FILE (a trained questioner policy .toml), or {PLUGIN_FORM}")
    return parse


def add_episode_options(parser: argparse.ArgumentParser, strategies, default_strategy: str,
                        defaults: EpisodeSettings = DEFAULTS) -> None:
    """--seed --turns --budget --change-every --strategy --task --kitchen, their defaults read from ``defaults``."""
    parser.add_argument("--seed", type=seed, default=defaults.seed,
                        help=f"one seed for every random choice (default {defaults.seed})")
    parser.add_argument("--turns", type=positive_int, default=defaults.turns,
                        help=f"time allocation T in turns (default {defaults.turns})")
    parser.add_argument("--budget", type=budget, default=defaults.budget,
                        help=f"question budget B in cost units (default {defaults.budget:g})")
    parser.add_argument("--change-every", type=positive_int, default=defaults.change_every,
                        help=f"a new scene every r turns (default {defaults.change_every})")
    parser.add_argument("--strategy", default=default_strategy, type=strategy_choice(strategies), metavar="STRATEGY",
                        help=f"questioning strategy: {', '.join(strategies)}, rl:FILE (a questioner policy from "
                             f"teachbot train-questioner), or {PLUGIN_FORM}: runs your code "
                             f"(default {default_strategy})")
    add_task_option(parser, defaults.task)
    add_kitchen_option(parser, defaults.kitchen)


TIME_FORMS = "a number of turns (e.g. --time 40) or of seconds ending in s (e.g. --time 600s)"


def time_allocation(text: str) -> tuple[str, float]:
    """``--time``: ``40`` (turns, a whole number >= 1) or ``600s`` (seconds, > 0, with --embodied-costs)."""
    raw = text.strip()
    unit = "seconds" if raw.lower().endswith("s") else "turns"
    number = raw[:-1].strip() if unit == "seconds" else raw
    try:
        value = _read_number(number, float if unit == "seconds" else int)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not {TIME_FORMS}") from None
    if unit == "seconds" and not (value > 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"'{text}' is not {TIME_FORMS}: seconds must be a positive number")
    if unit == "turns" and value < 1:
        raise argparse.ArgumentTypeError(f"'{text}' is not {TIME_FORMS}: turns must be at least 1")
    return unit, value


def add_time_options(parser: argparse.ArgumentParser) -> None:
    """``--time`` (turns or seconds) and ``--embodied-costs`` (thesis §8.2.2)."""
    parser.add_argument("--time", type=time_allocation, default=None, metavar="T",
                        help=f"time allocation: {TIME_FORMS}; seconds need --embodied-costs (default: --turns)")
    parser.add_argument("--embodied-costs", action="store_true",
                        help="a turn lasts what it takes in the simulation (the arm's motion, a pantry fetch, saying "
                             "the question, the teacher's answer); the time allocation is in seconds (default from "
                             "dialog/data/embodied-costs.toml) and DT weighs each question by its expected seconds")


def resolve_time(args, defaults: EpisodeSettings = DEFAULTS) -> tuple[int, float | None]:
    """(turns, seconds) from --turns, --time and --embodied-costs; a contradiction is one SettingsError line.

    Without --embodied-costs: turns only (``--time N`` is ``--turns N``). With it: the seconds of ``--time Ns``
    (or the data file's default allocation) and a turns cap: ``--time N``/``--turns N`` if given, else as many
    quiet turns as the seconds hold."""
    from dialog.embodied import default_allocation, load_embodied_costs
    from learning.errors import SettingsError
    from learning.limits import check_limit

    unit, value = args.time if args.time is not None else (None, None)
    turns_given = args.turns != defaults.turns
    if unit == "turns" and turns_given and args.turns != value:
        raise SettingsError(f"--time {value} and --turns {args.turns} both give the time allocation; give one")
    turns = int(value) if unit == "turns" else args.turns
    if not args.embodied_costs:
        if unit == "seconds":
            raise SettingsError(f"--time {value:g}s: a time in seconds needs --embodied-costs (without it the time "
                                f"allocation is in turns, e.g. --time {turns})")
        return turns, None
    seconds = float(value) if unit == "seconds" else default_allocation()
    check_limit("seconds", seconds, "--time")  # before the turns cap is worked out from it
    if unit != "turns" and not turns_given:
        turns = max(1, int(-(-seconds // load_embodied_costs().quiet)))
    return turns, seconds
