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
import sys

import dialog.commands
from dialog.threads import one_blas_thread


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="teachbot", description="A robot in a PyBullet kitchen that learns task words by asking questions.")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module_info in sorted(pkgutil.iter_modules(dialog.commands.__path__), key=lambda m: m.name):
        if module_info.name.startswith("_"):
            continue
        module = importlib.import_module(f"dialog.commands.{module_info.name}")
        module.register(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        with one_blas_thread():
            return int(args.handler(args) or 0)
    except (ValueError, RuntimeError, FileNotFoundError) as error:
        print(f"teachbot {args.command}: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
