"""The page's server: tornado in its own thread, on 127.0.0.1, every request and websocket checked.

Safe by default (docs/web.md, "Safety"): the server binds the loopback
address unless ``--allow-remote``; a random token made per session (as
Jupyter's) must come with every request and websocket; the Host header must
name this server and a websocket's Origin this page (which defeats DNS
rebinding and other sites' scripts); a message over
``dialog.web.messages.MAX_MESSAGE_BYTES`` is refused, one over
``WEBSOCKET_LIMIT_BYTES`` closes the socket. Every page of the session shares
one :class:`~dialog.web.teacher.WebTeacher`: a reload or a second tab rejoins.

The 3D view is the meshcat mirror (``bullet_world.viewer``): its page script is
served from the meshcat package and its websocket is relayed from the loopback
meshcat server, under the same token.
"""

from __future__ import annotations

import asyncio
import hmac
import ipaddress
import json
import secrets
import sys
import threading
from pathlib import Path
from urllib.parse import urlsplit

import tornado.httpserver
import tornado.netutil
import tornado.web
import tornado.websocket

from learning.errors import SettingsError, SetupError

STATIC = Path(__file__).with_name("static")
ASSETS = {"app.js": "application/javascript", "forms.js": "application/javascript",
          "diffuse.js": "application/javascript", "style.css": "text/css"}
WEBSOCKET_LIMIT_BYTES = 1 << 16
LOOPBACK = "127.0.0.1"
SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data: blob:; style-src 'self' 'unsafe-inline'; "
                               "script-src 'self' 'unsafe-eval'; connect-src 'self' ws: wss:; frame-ancestors 'none'",
    "X-Frame-Options": "DENY", "Referrer-Policy": "no-referrer", "Cache-Control": "no-store",
    "X-Content-Type-Options": "nosniff",
}


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_host(host: str, allow_remote: bool) -> None:
    """A host other than loopback only with ``--allow-remote``."""
    if not is_loopback(host) and not allow_remote:
        raise SettingsError(f"--host {host} would let other machines reach the page; accepted: 127.0.0.1 (the "
                            "default), or add --allow-remote (see docs/web.md for a reverse proxy with TLS)")


def public_origin(origin: str) -> tuple[str, str]:
    """The scheme and host of an ``--origin`` (a reverse proxy's public address)."""
    parts = urlsplit(origin)
    if parts.scheme not in ("http", "https") or not parts.netloc or parts.path not in ("", "/") or parts.query:
        raise SettingsError(f"--origin {origin}; accepted: scheme and host only, such as https://study.example.org")
    return parts.scheme, parts.netloc


def meshcat_script() -> Path | None:
    """meshcat's page script (three.js and the viewer), shipped in the meshcat package."""
    try:
        import meshcat.servers.zmqserver as zmqserver
    except ImportError:
        return None
    path = Path(zmqserver.VIEWER_ROOT) / "main.min.js"
    return path if path.is_file() else None


class _Checked:
    """Host and token checks shared by the page's handlers and websockets."""

    server: WebServer

    def initialize(self, server: WebServer) -> None:
        self.server = server

    def set_default_headers(self) -> None:  # every response, refusals and errors too
        for name, value in SECURITY_HEADERS.items():
            self.set_header(name, value)

    def refuse_unless_allowed(self) -> None:
        request = self.request
        if request.host not in self.server.hosts:
            self.server.log_refusal(f"a request for host {request.host!r}")
            raise tornado.web.HTTPError(403, reason="Wrong host")
        token = request.query_arguments.get("token", [b""])[-1].decode("utf-8", "replace")
        if not hmac.compare_digest(token.encode(), self.server.token.encode()):
            self.server.log_refusal(f"{request.method} {request.path} with {'a wrong' if token else 'no'} token")
            raise tornado.web.HTTPError(403, reason="Wrong or missing token")


class _Handler(_Checked, tornado.web.RequestHandler):
    def prepare(self) -> None:
        self.refuse_unless_allowed()

    def write_error(self, status_code: int, **kwargs) -> None:
        self.set_header("Content-Type", "text/plain; charset=utf-8")
        self.finish(f"{status_code} {self._reason}: open the page with the URL teachbot printed.\n")


class NotFoundHandler(_Handler):
    """Any path outside the routes: 404, with the security headers as every response."""

    def prepare(self) -> None:
        raise tornado.web.HTTPError(404, reason="Not found")


class PageHandler(_Handler):
    def get(self) -> None:
        html = (STATIC / "index.html").read_text(encoding="utf-8")
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.finish(html.replace("{{token}}", self.server.token).replace("{{title}}", self.server.title))


class AssetHandler(_Handler):
    def get(self, name: str) -> None:
        if name not in ASSETS:
            raise tornado.web.HTTPError(404)
        self.set_header("Content-Type", ASSETS[name])
        self.finish((STATIC / name).read_bytes())


class MeshcatScriptHandler(_Handler):
    def get(self) -> None:
        script = meshcat_script()
        if script is None:
            raise tornado.web.HTTPError(404)
        self.set_header("Content-Type", "application/javascript")
        self.finish(script.read_bytes())


class PictureHandler(_Handler):
    def get(self, question: str) -> None:
        path = self.server.teacher.picture_path(int(question))
        if path is None or not Path(path).is_file():
            raise tornado.web.HTTPError(404)
        self.set_header("Content-Type", "image/png")
        self.finish(Path(path).read_bytes())


class _Socket(_Checked, tornado.websocket.WebSocketHandler):
    def prepare(self) -> None:
        self.refuse_unless_allowed()
        origin = self.request.headers.get("Origin")
        if origin is None:  # every browser sends it; a page of this server has this one
            self.server.log_refusal("a websocket without an Origin")
            raise tornado.web.HTTPError(403, reason="No origin")
        if origin not in self.server.origins:  # checked here: tornado skips check_origin when the host matches
            self.server.log_refusal(f"a websocket from the foreign origin {origin!r}")
            raise tornado.web.HTTPError(403, reason="Foreign origin")

    def check_origin(self, origin: str) -> bool:
        return origin in self.server.origins  # prepare refused every other origin already


class SessionSocket(_Socket):
    """The page's conversation: state and lines out, answers in (each checked by the teacher)."""

    def open(self) -> None:
        self.server.sockets.add(self)
        self.write_message(json.dumps(self.server.teacher.snapshot()))

    def on_message(self, message) -> None:
        refused = self.server.teacher.submit(message)
        if refused is not None:
            self.write_message(json.dumps({"type": "refused", "reason": refused}))

    def on_close(self) -> None:
        self.server.sockets.discard(self)


class MeshcatSocket(_Socket):
    """The meshcat mirror's commands, relayed from the loopback meshcat server to the page's 3D view."""

    upstream = None

    async def open(self) -> None:
        url = self.server.meshcat_socket_url
        if url is None:
            self.close()
            return
        try:
            self.upstream = await tornado.websocket.websocket_connect(url, max_message_size=1 << 28)
        except OSError:
            self.close()
            return
        asyncio.ensure_future(self._relay())

    async def _relay(self) -> None:
        while self.upstream is not None:
            message = await self.upstream.read_message()
            if message is None:
                break
            try:
                await self.write_message(message, binary=isinstance(message, bytes))
            except tornado.websocket.WebSocketClosedError:
                break
        self.close()

    def on_message(self, message) -> None:
        pass  # the 3D view only receives

    def on_close(self) -> None:
        if self.upstream is not None:
            self.upstream.close()
            self.upstream = None


class WebServer:
    """The session's page at ``url``, served from a thread of this process until :meth:`close`."""

    def __init__(self, teacher, *, host: str = LOOPBACK, port: int = 0, allow_remote: bool = False,
                 origins: tuple[str, ...] = (), title: str = "teachbot", log=None):
        check_host(host, allow_remote)
        self.teacher, self.title, self.log = teacher, title, log or sys.stderr
        self.token = secrets.token_urlsafe(24)
        self.sockets: set[SessionSocket] = set()
        self.meshcat_socket_url: str | None = None  # the 3D view's meshcat server, once a kitchen is attached
        try:
            sockets = tornado.netutil.bind_sockets(port, address=host)
        except OSError as error:
            raise SettingsError(f"--port {port} on {host}: {error.strerror or error}; accepted: a free port, or 0 "
                                "for any") from None
        self.port = int(sockets[0].getsockname()[1])
        shown_host = host if ":" not in host else f"[{host}]"
        self.hosts = {f"{shown_host}:{self.port}"} | ({f"localhost:{self.port}", f"127.0.0.1:{self.port}"}
                                                      if is_loopback(host) else set())
        self.origins = {f"http://{name}" for name in self.hosts}
        for origin in origins:  # a reverse proxy's public address (docs/web.md)
            scheme, netloc = public_origin(origin)
            self.origins.add(f"{scheme}://{netloc}")
            self.hosts.add(netloc)
        self.url = f"http://{shown_host}:{self.port}/?token={self.token}"
        self.refusals = 0
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stopped: asyncio.Event | None = None
        ready, failure = threading.Event(), []
        self._thread = threading.Thread(target=self._serve, args=(sockets, ready, failure), name="teachbot-web",
                                        daemon=True)
        self._thread.start()
        ready.wait(30)
        if failure or self._loop is None:
            raise SetupError(f"the web server did not start: {failure[0] if failure else 'no answer in 30 s'}")
        teacher.broadcast = self.broadcast

    def application(self) -> tornado.web.Application:
        handlers = [(r"/", PageHandler), (r"/static/([a-z.]+)", AssetHandler), (r"/meshcat.js", MeshcatScriptHandler),
                    (r"/picture/([0-9]{1,9})", PictureHandler), (r"/ws", SessionSocket),
                    (r"/meshcat-ws", MeshcatSocket)]
        return tornado.web.Application([(path, handler, {"server": self}) for path, handler in handlers],
                                       default_handler_class=NotFoundHandler, default_handler_args={"server": self},
                                       websocket_max_message_size=WEBSOCKET_LIMIT_BYTES,
                                       log_function=lambda handler: None)

    def _serve(self, sockets, ready: threading.Event, failure: list) -> None:
        async def main() -> None:
            self._loop, self._stopped = asyncio.get_running_loop(), asyncio.Event()
            server = tornado.httpserver.HTTPServer(self.application(), max_body_size=WEBSOCKET_LIMIT_BYTES)
            server.add_sockets(sockets)
            ready.set()
            await self._stopped.wait()
            server.stop()
            for socket in list(self.sockets):
                socket.close()
            await server.close_all_connections()
        try:
            asyncio.run(main())
        except Exception as error:  # reported to the starting thread
            failure.append(f"{type(error).__name__}: {error}")
            ready.set()

    def log_refusal(self, what: str) -> None:
        self.refusals += 1
        print(f"web: refused {what}", file=self.log, flush=True)

    def broadcast(self, message: dict) -> None:
        """Send ``message`` to every open page (from any thread)."""
        if self._loop is None:
            return
        text = json.dumps(message)  # ASCII: whatever a line holds, it reaches the page (a lone surrogate has no UTF-8)

        def send() -> None:
            for socket in list(self.sockets):
                try:
                    socket.write_message(text)
                except tornado.websocket.WebSocketClosedError:
                    self.sockets.discard(socket)
        try:
            self._loop.call_soon_threadsafe(send)
        except RuntimeError:  # the loop has closed
            pass

    def close(self) -> None:
        if self._loop is not None and self._stopped is not None and self._thread.is_alive():
            try:
                self._loop.call_soon_threadsafe(self._stopped.set)
            except RuntimeError:
                pass
            self._thread.join(10)


def meshcat_socket(web_url: str | None) -> str | None:
    """The meshcat server's websocket (``ws://127.0.0.1:PORT/``) from its page URL."""
    if not web_url:
        return None
    parts = urlsplit(web_url)
    return f"ws://{parts.netloc}/"
