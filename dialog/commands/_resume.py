"""``teach --resume``: options given beside it must agree with the recorded session, which keeps its settings."""

from __future__ import annotations

import argparse
from pathlib import Path

from dialog.printed_command import command_line
from dialog.user_weights import check_weights_unchanged, weights_from_header
from learning.errors import TranscriptError

# option: (attribute of the parsed arguments, the recorded session's value of it)
SESSION_OPTIONS = {
    "--task": ("task", lambda s: s.task),
    "--kitchen": ("kitchen", lambda s: s.kitchen),
    "--strategy": ("strategy", lambda s: s.strategy),
    "--seed": ("seed", lambda s: s.seed),
    "--turns": ("turns", lambda s: s.turns),
    "--budget": ("budget", lambda s: s.budget),
    "--change-every": ("change_every", lambda s: s.change_every),
    "--realtime": ("realtime", lambda s: s.realtime),
    "--teacher": ("teacher", lambda s: s.teacher["kind"]),
    "--replay": ("replay", lambda s: s.teacher.get("transcript")),
    "--mislabel-rate": ("mislabel_rate", lambda s: s.teacher.get("mislabel_rate", 0.0)),
    "--dont-know-rate": ("dont_know_rate", lambda s: s.teacher.get("dont_know_rate", 0.0)),
    "--feature-quality": ("feature_quality", lambda s: s.teacher.get("feature_quality", 1.0)),
    "--answer-delay": ("answer_delay", lambda s: s.teacher.get("answer_delay", 0.0)),
    "--no-fetch": ("no_fetch", lambda s: not s.fetch_from_pantry),
    "--weights": ("weights", lambda s: None if s.weights is None else s.weights["file"]),
    "--embodied-costs": ("embodied_costs", lambda s: s.seconds is not None),
    "--time": ("time", lambda s: ("turns", s.turns) if s.seconds is None else ("seconds", s.seconds)),
}


def _same(given, recorded) -> bool:
    if isinstance(given, Path) or isinstance(recorded, Path):
        return recorded is not None and Path(given).resolve() == Path(recorded).resolve()
    return given == recorded


def differing_options(args: argparse.Namespace, settings, path: Path, defaults: argparse.Namespace) -> list[str]:
    """``--option GIVEN differs from the recorded VALUE`` for every option given beside --resume that the
    recorded session contradicts."""
    found = []
    for option, (name, recorded_value) in SESSION_OPTIONS.items():
        if not hasattr(args, name):
            continue
        given, recorded = getattr(args, name), recorded_value(settings)
        if given != getattr(defaults, name, None) and not _same(given, recorded):
            found.append(f"{option} {_shown(given)} differs from the recorded {_shown(recorded)}")
    transcript = getattr(args, "transcript", None)
    if transcript is not None and Path(transcript).resolve() != Path(path).resolve():
        found.append(f"--transcript {transcript} differs from the recorded session's file (it goes on in {path})")
    return found


def _shown(value) -> str:
    """A value as a person writes it: ``10.0`` is 10, ``0.5`` is 0.5, anything else as it is."""
    return f"{value:g}" if isinstance(value, float) else str(value)


def check_resume_options(args: argparse.Namespace, settings, path: Path, defaults: argparse.Namespace) -> None:
    """Refuse options beside --resume that differ from the recorded session (``defaults``: what the command parses
    when no option is given), naming each of them, and a weights file that changed since it was recorded."""
    differing = differing_options(args, settings, path, defaults)
    if differing:
        raise TranscriptError(f"{path}: a resumed session keeps its recorded settings, but {'; '.join(differing)}; "
                              f"leave {'it' if len(differing) == 1 else 'them'} out, or start a new session without "
                              f"--resume")
    if settings.weights is not None:
        check_weights_unchanged(weights_from_header(settings.weights, path), path)


# Options of a run that its files do not record, so a "continue with" line must repeat them: (option, attribute)
UNRECORDED_TEACH_OPTIONS = (("--pictures", "pictures"), ("--no-pictures", "no_pictures"), ("--viewer", "viewer"),
                            ("--viewer-export", "viewer_export"), ("--viewer-hold", "viewer_hold"))


def continue_command(words: list, args: argparse.Namespace | None = None, options=UNRECORDED_TEACH_OPTIONS) -> str:
    """The command that goes on where a run stopped: the program as it was started, ``words`` (the command and
    what names the run) and every option of ``options`` that ``args`` gave, runnable as printed
    (``dialog.printed_command``)."""
    command = [str(word) for word in words]
    for option, attribute in options if args is not None else ():
        value = getattr(args, attribute, None)
        if value is True:
            command.append(option)
        elif isinstance(value, (list, tuple)):  # a repeatable option (--origin)
            for item in value:
                command += [option, str(item)]
        elif value not in (None, False):
            command += [option, f"{value:g}" if isinstance(value, float) else str(value)]
    return command_line(command)
