"""``--web`` for the commands that run a session: the options, and the page, its server and 3D view together.

Wiring, in a command module::

    add_web_options(parser)                          # in register()
    with WebPage.open(args, environment) as page:    # in run(), when args.web
        manager, records = open_session(..., teacher=page.teacher, observers=page.observers)
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

from dialog.commands._arguments import number_within
from dialog.web.server import LOOPBACK, WebServer, check_host, is_loopback, meshcat_socket, public_origin
from dialog.web.teacher import WebTeacher
from learning.errors import SettingsError


def add_web_options(parser: argparse.ArgumentParser, what: str = "answer the robot's questions") -> None:
    group = parser.add_argument_group("web page")
    group.add_argument("--web", action="store_true",
                       help=f"{what} in a browser page instead of the terminal (the URL is printed; 127.0.0.1 only)")
    group.add_argument("--host", default=LOOPBACK, help="with --web: the address to serve on (default 127.0.0.1; "
                                                        "another needs --allow-remote)")
    group.add_argument("--port", type=_port, default=0, help="with --web: the port (default: any free one)")
    group.add_argument("--allow-remote", action="store_true",
                       help="with --web: allow --host other than loopback (prints what it exposes; docs/web.md)")
    group.add_argument("--no-3d", dest="no_3d", action="store_true",
                       help="with --web: no 3D view, the camera picture only (lighter for a slow machine or browser)")
    group.add_argument("--origin", action="append", default=[], metavar="URL",
                       help="with --web: a reverse proxy's public address the page may come from, e.g. "
                            "https://study.example.org (repeatable)")


_port = number_within(int, 0, 65535, "a port number from 0 to 65535")


def check_web_options(args: argparse.Namespace) -> None:
    """The page's options make sense together (checked before anything starts)."""
    if not getattr(args, "web", False):
        given = [name for name, default in (("--host", LOOPBACK), ("--port", 0), ("--allow-remote", False),
                                            ("--origin", []), ("--no-3d", False))
                 if getattr(args, name[2:].replace("-", "_"), default) != default]
        if given:
            raise SettingsError(f"{', '.join(given)} only {'goes' if len(given) == 1 else 'go'} with --web")
        return
    check_host(args.host, args.allow_remote)
    for origin in args.origin:
        public_origin(origin)


def web_continue_options(args: argparse.Namespace) -> tuple:
    """The page's options a "continue with" line repeats, as (option, attribute): with --web, the command that
    goes on must open the page again (the address only where it is not the default)."""
    if not getattr(args, "web", False):
        return ()
    return tuple((option, name) for option, name in (("--web", "web"), ("--host", "host"), ("--port", "port"),
                                                     ("--allow-remote", "allow_remote"), ("--origin", "origin"),
                                                     ("--no-3d", "no_3d"))
                 if name != "host" or args.host != LOOPBACK)


WAIT_FOR_PAGE_S = 60.0
MIRROR_WAIT_S = 2.0  # the longest a question waits for the 3D view's mirror (a stuck meshcat server stops it)
# While the robot works the page draws its 3D view at most 3 times a second (app.js, BUSY_3D_FPS), so the
# mirror sends the moving arm to it at twice that, not at the stand-alone viewer's 30: each frame sent costs the
# session, meshcat's server and the page's main thread their share of the 2 cores the robot needs.
PAGE_MIRROR_FPS = 6.0


class Watcher:
    """A dialog observer that shows a scripted episode in the page as it happens (``demo --web``): each question
    with the numbered camera picture of its scene, drawn once a scene (while the arm rests out of the camera's
    view, before the turn's pace is waited) into ``pictures`` (a folder).

    Its lines go to the page only: the terminal prints the episode's own lines already."""

    def __init__(self, teacher, environment=None, pictures: Path | None = None):
        self.teacher, self.environment, self.pictures = teacher, environment, pictures
        self.turn = 0
        self.picture: str | None = None

    def on_scene(self, scene=None) -> None:
        if hasattr(self.environment, "scene_picture") and scene is not None and self.pictures is not None:
            path = self.pictures / f"scene-from-turn-{self.turn + 1:03d}.png"
            self.picture = str(self.environment.scene_picture(scene, path))
        self.teacher.say(f"-- turn {self.turn + 1}: the robot looks at a new scene of "
                         f"{getattr(scene, 'n_objects', '?')} objects", echo=False)

    def on_question(self, action, text=None, scene=None) -> None:
        index = getattr(action, "object_index", None)
        self.teacher.watch(self.turn + 1, str(getattr(action, "kind", "")), text or "",
                           None if index is None else int(index) + 1, self.picture)

    def on_answer(self, action, outcome=None, scene=None) -> None:
        self.teacher.heard(getattr(outcome, "raw", "") or f"({getattr(outcome, 'kind', 'no answer')})")

    def on_turn(self, record=None, scene=None) -> None:
        self.turn += 1
        if isinstance(record, dict) and record.get("action", {}).get("kind") == "none":
            self.teacher.say(f"Turn {self.turn}: the robot stays quiet.", echo=False)


class WebPage:
    """The page for one session or one participant's run: a :class:`WebTeacher`, the server, and the live 3D
    view of the kitchen being taught (``attach``; a study attaches each session's kitchen in turn)."""

    def __init__(self, args: argparse.Namespace, title: str = "Teaching the robot", out=None, three_d: bool = True):
        self.out = out or sys.stdout
        self.args, self.three_d = args, three_d and not getattr(args, "no_3d", False)
        self.teacher = WebTeacher(echo=self.out)
        self.viewer = None
        self.environment = None
        self._pictures: Path | None = None  # a watched demo's camera pictures (a temporary folder)
        self.server = WebServer(self.teacher, host=args.host, port=args.port, allow_remote=args.allow_remote,
                                origins=tuple(args.origin), title=title)
        if args.allow_remote and not is_loopback(args.host):
            print(f"warning: --allow-remote: the page is served on {args.host}:{self.server.port} without TLS. Anyone "
                  "who can reach it and has the URL (its token) sees the camera pictures, the 3D view and the "
                  "conversation, and can answer the robot; put it behind a reverse proxy with TLS (docs/web.md)",
                  file=sys.stderr, flush=True)
        print(f"Open the page: {self.server.url}", file=self.out, flush=True)

    @classmethod
    def for_session(cls, args: argparse.Namespace, environment, **options) -> WebPage:
        page = cls(args, **options)
        try:
            page.attach(environment)
        except BaseException:
            page.close()
            raise
        return page

    def attach(self, environment) -> None:
        """Show ``environment``'s kitchen: clicks on its camera picture, its 3D view (when meshcat starts)."""
        self.detach()
        self.environment = environment
        self.teacher.locate = getattr(environment, "picture_pixels", None)
        if self.three_d and getattr(environment, "world", None) is not None:
            from dialog.viewer import start_viewer

            export = getattr(self.args, "viewer_export", None)
            self.viewer = start_viewer(argparse.Namespace(viewer=True, viewer_export=export), environment.world,
                                       live_fps=PAGE_MIRROR_FPS, panels=False)  # the page has the words
        self.server.meshcat_socket_url = meshcat_socket(getattr(self.viewer, "url", None))
        self.teacher.new_view(self.viewer is not None)

    def detach(self) -> None:
        if self.viewer is not None:
            from dialog.viewer import stop_viewer

            viewer, self.viewer = self.viewer, None
            self.server.meshcat_socket_url = None
            stop_viewer(viewer)

    @property
    def url(self) -> str:
        return self.server.url

    @property
    def observers(self) -> tuple:
        return (self.viewer, self) if self.viewer is not None else (self,)

    def on_scene(self, scene=None) -> None:
        """A new scene: tell the page which 3D node is which object, for clicks in the 3D view."""
        if self.viewer is not None:
            nodes = {node.rsplit("/", 1)[-1]: index + 1 for index, node in enumerate(self.viewer.reader.object_nodes)}
            self.teacher.set_nodes(nodes)

    def on_question(self, action=None, text=None, scene=None) -> None:
        """Before the question goes to the page: the 3D view's mirror (an observer before this one) hands meshcat
        the arm's final pose and the question's highlight first, so that the page gets them with the question
        and draws them at once, in one frame, instead of piece by piece after it."""
        if self.viewer is not None and self.viewer.thread.live:
            self.viewer.thread.drain(MIRROR_WAIT_S)

    def wait_for_viewer_page(self, timeout_s: float = WAIT_FOR_PAGE_S) -> bool:
        """Wait until a browser has the page open (a demo should not end before anyone sees it); False if none
        came within ``timeout_s`` (the episode then goes on anyway)."""
        print(f"Waiting for a browser to open the page (up to {timeout_s:g} s; Ctrl-C stops)", file=self.out,
              flush=True)
        end = time.monotonic() + timeout_s
        while not self.server.sockets:
            if time.monotonic() > end:
                return False
            time.sleep(0.1)
        return True

    def watcher(self) -> Watcher:
        if self._pictures is None:
            self._pictures = Path(tempfile.mkdtemp(prefix="teachbot-demo-pictures-"))
        return Watcher(self.teacher, self.environment, self._pictures)

    def close(self, text: str = "") -> None:
        """The session is over: the page says so (``text``: the summary, or why it stopped; without it, what it
        said already), then the server and the 3D view stop."""
        self.teacher.end(text)
        self.server.close()
        self.detach()
        if self._pictures is not None:
            shutil.rmtree(self._pictures, ignore_errors=True)
            self._pictures = None
