"""The ``teachbot`` command line.

Each subcommand lives in its own module under ``dialog/commands/`` and exposes
``register(subparsers)``, which adds its parser and sets ``handler`` to a
function taking the parsed arguments and returning an exit code. Modules are
discovered, so adding a command means adding a module.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import signal
import sys

import dialog.commands
from dialog import software_version
from dialog.commands._arguments import TeachbotParser
from dialog.interrupts import CleanSignals, exit_code
from dialog.threads import one_blas_thread
from learning.errors import TeachbotError


def build_parser() -> argparse.ArgumentParser:
    parser = TeachbotParser(
        prog="teachbot", description="A robot in a PyBullet kitchen that learns task words by asking questions.")
    parser.add_argument("--version", action="version", version=software_version())
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module_info in sorted(pkgutil.iter_modules(dialog.commands.__path__), key=lambda m: m.name):
        if module_info.name.startswith("_"):
            continue
        module = importlib.import_module(f"dialog.commands.{module_info.name}")
        module.register(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; Ctrl-C at any moment ends it with "Interrupted." and 130, SIGTERM/SIGHUP with 128 + N.

    Once a signal has arrived, whatever error reaches here is its doing (C code, an import, may turn
    the KeyboardInterrupt into another error), so it ends the same way. Called with no ``argv`` (the
    ``teachbot`` program), signals during the interpreter's shutdown end the process quietly too.
    """
    args = None
    signals = CleanSignals(keep_after=argv is None)
    with signals:
        try:
            args = build_parser().parse_args(argv)
            with one_blas_thread():
                return int(args.handler(args) or 0)
        except BaseException as error:
            command = "teachbot" if args is None else f"teachbot {args.command}"
            if signals.signum is not None:
                return _report_signal(command, signals.signum)
            if isinstance(error, TeachbotError):  # bad input: one line; anything else is a bug and shows its traceback
                print(f"{command}: {error}", file=sys.stderr)
                return 2
            raise


def _report_signal(command: str, signum: int) -> int:
    if signum == signal.SIGINT:
        print("\nInterrupted.", file=sys.stderr, flush=True)
    else:
        print(f"\n{command}: stopped by {signal.Signals(signum).name}.", file=sys.stderr, flush=True)
    return exit_code(signum)


if __name__ == "__main__":
    sys.exit(main())
