"""``--viewer`` and ``--viewer-export`` for every command that runs the simulated kitchen.

Wiring, in a command module::

    add_viewer_option(parser)                                   # in register()
    with viewer_observers(args, environment.world) as observers:  # in run()
        manager = build_episode(settings, environment, ..., observers=observers)
        result = manager.run()

If the viewer can't start, one warning line goes to standard error and the
session goes on headless. ``hold_viewer(args, viewer)`` after the summary keeps a
live viewer up until Enter (in a terminal) or for ``--viewer-hold SECONDS``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from dialog.commands._arguments import seconds
from dialog.output_paths import check_writable, file_argument, from_os_error, numbered, path_problem
from learning.errors import OutputPathError


def add_viewer_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--viewer`` (live meshcat mirror) and ``--viewer-export HTML`` (the episode as one page)."""
    group = parser.add_argument_group("viewer")
    group.add_argument("--viewer", action="store_true",
                       help="show the kitchen live in meshcat (the URL is printed; it listens on 127.0.0.1 only)")
    group.add_argument("--viewer-export", type=file_argument, default=None, metavar="HTML",
                       help="write the episode as one static HTML page with meshcat's animation (opens without "
                            "a server)")
    group.add_argument("--viewer-hold", type=seconds, default=None, metavar="SECONDS",
                       help="with --viewer: keep the viewer up this long after the end (default: until Enter when "
                            "run in a terminal, not at all otherwise; 0: close at once)")


def start_viewer(args: argparse.Namespace, world, **options):
    """The viewer the options ask for, or None (nothing asked, or it could not start: one warning line).
    ``options`` go to the :class:`~bullet_world.viewer.mirror.Viewer` (``live_fps``: how often it mirrors a
    moving arm)."""
    live = bool(getattr(args, "viewer", False))
    export = checked_export(getattr(args, "viewer_export", None))
    if not live and export is None:
        return None
    try:
        from bullet_world.viewer.mirror import Viewer

        viewer = Viewer(world, live=live, export_path=export, **options)
    except Exception as error:  # any failure to start leaves the session headless
        print(f"warning: the viewer did not start ({type(error).__name__}: {error}); going on without it",
              file=sys.stderr)
        return None
    if viewer.url:
        print(f"Viewer: {viewer.url}", file=sys.stderr)
    return viewer


def hold_viewer(args: argparse.Namespace, viewer, stdin=None, out=None) -> float:
    """Keep a live viewer up at the end: until Enter when stdin is a terminal (not under CI), or for
    ``--viewer-hold`` seconds; Ctrl-C ends the hold. Returns the seconds held."""
    url = getattr(viewer, "url", None)
    hold = getattr(args, "viewer_hold", None)
    stdin, out = stdin or sys.stdin, out or sys.stderr
    if not url or hold == 0 or (hold is None and not _interactive(stdin)):
        return 0.0
    started = time.monotonic()
    try:
        if hold is None:
            print(f"The viewer stays at {url}; press Enter to close it", file=out, flush=True)
            stdin.readline()
        else:
            print(f"The viewer stays at {url} for {hold:g} s (Ctrl-C closes it)", file=out, flush=True)
            time.sleep(hold)
    except KeyboardInterrupt:
        print("", file=out, flush=True)
    return time.monotonic() - started


def _interactive(stream) -> bool:
    """Whether a person can press Enter on ``stream``: a terminal, and not a CI run."""
    if os.environ.get("CI"):
        return False
    try:
        return stream.isatty()
    except (AttributeError, OSError, ValueError):
        return False


def stop_viewer(viewer) -> dict | None:
    """Close the viewer (writing its export, if asked for); a failure is a warning, never an error."""
    if viewer is None:
        return None
    try:
        written = viewer.close()
    except OSError as error:
        print(f"warning: {from_os_error(error, viewer.export_path, 'viewer export')}; the session itself is saved",
              file=sys.stderr)
        return None
    except Exception as error:  # the session's own results matter more than the picture of it
        print(f"warning: the viewer did not close cleanly ({type(error).__name__}: {error})", file=sys.stderr)
        return None
    if written:
        print(page_written("Episode page", written, f", {written['seconds']:.0f} s of animation"), file=sys.stderr)
    return written


def page_written(label: str, written: dict, more: str = "") -> str:
    """What an exported page is and how to open it (it needs no server, so no URL of one that has exited):
    ``Page: scene.html (3.1 MB), one self-contained HTML file; open it in a web browser: file:///...``."""
    path = Path(written["path"])
    return (f"{label}: {path} ({written['bytes'] / 1e6:.1f} MB{more}), one self-contained HTML file that needs no "
            f"server; open it in a web browser: {path.resolve().as_uri()}")


def page_path(path: Path, name: str) -> Path:
    """``path``, or ``path/name`` when ``path`` is a folder (numbered as ``name-2.html``, ... when taken, so an
    earlier page is kept; said on standard error); a path that can't even be looked up (a name too long, a loop of
    links) is refused by ``check_writable``."""
    if not path_problem(path) and path.is_dir():
        page = numbered(path / name)
        print(f"{path} is a folder: the page goes to {page}", file=sys.stderr)
        return page
    return path


def checked_export(path: Path | None) -> Path | None:
    """The ``--viewer-export`` file to write, or None: one that can't be written is a warning (it is optional)."""
    if path is None:
        return None
    path = page_path(path, "episode.html")
    try:
        return check_writable(path, "viewer export")
    except OutputPathError as error:
        print(f"warning: {error}; going on without the episode page", file=sys.stderr)
        return None


@contextmanager
def viewer_observers(args: argparse.Namespace, world):
    """Dialog observers for the options: ``(viewer,)`` or ``()``; the viewer is closed on the way out."""
    viewer = start_viewer(args, world)
    try:
        yield (viewer,) if viewer is not None else ()
    finally:
        stop_viewer(viewer)


DEFAULT_PACE_S = 1.5  # seconds a turn lasts at least when someone watches (--viewer, --web), so they can follow


class Pacer:
    """A dialog observer that makes each turn last at least ``seconds`` of wall time (``--pace``).

    It only waits: the episode, its clock and its transcript are the same with any pace. It goes first among
    the observers, so that a question is shown (viewer, page) once its wait is over.
    """

    def __init__(self, seconds: float):
        self.seconds = float(seconds)
        self._turn_started: float | None = None

    def on_scene(self, scene=None) -> None:
        if self._turn_started is None:  # the first turn begins (building the held-out set came before)
            self._turn_started = time.monotonic()

    def on_question(self, action=None, text=None, scene=None) -> None:
        self._wait(0.5)  # the question is on the page before its answer comes

    def on_turn(self, record=None, scene=None) -> None:
        self._wait(1.0)
        self._turn_started = time.monotonic()

    def _wait(self, share: float) -> None:
        if self._turn_started is None:
            self._turn_started = time.monotonic()
        left = self._turn_started + share * self.seconds - time.monotonic()
        if left > 0:
            time.sleep(left)


def pace_of(args: argparse.Namespace) -> float:
    """``--pace``, or its default: DEFAULT_PACE_S when the episode is watched (--viewer, --web), else 0."""
    if getattr(args, "pace", None) is not None:
        return float(args.pace)
    watched = bool(getattr(args, "viewer", False) or getattr(args, "web", False))
    return DEFAULT_PACE_S if watched else 0.0
