"""The loopback meshcat server as a child process, and a quiet, pipelined connection to it.

:class:`LocalServer` runs :mod:`bullet_world.viewer.server_process` (the web
page and the ZeroMQ socket both on 127.0.0.1) and stops it again;
:class:`QuietWindow` talks to it with time limits, so a dead server raises
:class:`ViewerError` instead of blocking the session.
"""

from __future__ import annotations

import os
import selectors
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import umsgpack
import zmq
from meshcat.visualizer import ViewerWindow

from learning.errors import SetupError

LOOPBACK = "127.0.0.1"
SERVER_SCRIPT = Path(__file__).with_name("server_process.py")
START_TIMEOUT_S = 20.0
REPLY_TIMEOUT_MS = 10_000
MAX_PENDING = 256


class ViewerError(SetupError):
    """The meshcat server could not be started or stopped answering."""


class LocalServer:
    """The loopback meshcat server as a child process of this one."""

    def __init__(self, timeout_s: float = START_TIMEOUT_S):
        self._log = tempfile.TemporaryFile()
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        # the child follows this process: it exits when its stdin (held open here) closes or this process dies
        self.process = subprocess.Popen([sys.executable, "-u", str(SERVER_SCRIPT), "--parent", str(os.getpid())],
                                        stdout=subprocess.PIPE, stderr=self._log, stdin=subprocess.PIPE, env=env)
        try:
            self.zmq_url, self.web_url = self._read_addresses(timeout_s)
        except ViewerError:
            self.stop()
            raise

    def _read_addresses(self, timeout_s: float) -> tuple[str, str]:
        found: dict[str, str] = {}
        deadline = time.monotonic() + timeout_s
        buffer = b""
        with selectors.DefaultSelector() as selector:
            selector.register(self.process.stdout, selectors.EVENT_READ)
            while len(found) < 2:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise ViewerError(f"the meshcat server did not start within {timeout_s:g} s")
                if not selector.select(left):
                    continue
                chunk = os.read(self.process.stdout.fileno(), 4096)
                if not chunk:
                    raise ViewerError(f"the meshcat server exited while starting: {self._tail()}")
                buffer += chunk
                *lines, buffer = buffer.split(b"\n")
                for line in lines:
                    key, _, value = line.decode("utf-8", "replace").strip().partition("=")
                    if key in ("zmq_url", "web_url"):
                        found[key] = value
        return found["zmq_url"], found["web_url"]

    def _tail(self) -> str:
        self._log.seek(0)
        lines = self._log.read().decode("utf-8", "replace").strip().splitlines()
        return lines[-1] if lines else f"exit code {self.process.poll()}"

    def stop(self) -> None:
        """Stop the child process (terminate, then kill if it lingers)."""
        if self.process.stdin is not None:
            self.process.stdin.close()
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self.process.stdout is not None:
            self.process.stdout.close()
        self._log.close()


class QuietWindow(ViewerWindow):
    """meshcat's window without the banner, pipelined, with reply time limits.

    meshcat's own window waits for the server's reply after every command; with the server,
    the browser and the simulation sharing two cores, each round trip costs milliseconds. This
    window talks to the server's REP socket through a DEALER socket: it sends up to
    ``MAX_PENDING`` commands before collecting their replies (:meth:`flush`), in order.
    """

    def __init__(self, zmq_url: str, web_url: str, timeout_ms: int = REPLY_TIMEOUT_MS):
        self.server_proc = None
        self.zmq_url, self.web_url, self.timeout_ms = zmq_url, web_url, timeout_ms
        self.pending = 0
        self.connect_zmq()

    def connect_zmq(self):
        self.zmq_socket = self.context.socket(zmq.DEALER)
        self.zmq_socket.setsockopt(zmq.RCVTIMEO, self.timeout_ms)
        self.zmq_socket.setsockopt(zmq.SNDTIMEO, self.timeout_ms)
        self.zmq_socket.setsockopt(zmq.LINGER, 0)
        self.zmq_socket.connect(self.zmq_url)
        self.pending = 0

    def _request(self, *frames: bytes) -> None:
        try:
            self.zmq_socket.send_multipart([b"", *frames])
        except zmq.error.Again:
            raise ViewerError("the meshcat server stopped answering") from None
        self.pending += 1
        if self.pending >= MAX_PENDING:
            self.flush()

    def _reply(self) -> bytes:
        try:
            reply = self.zmq_socket.recv_multipart()
        except zmq.error.Again:
            raise ViewerError("the meshcat server stopped answering") from None
        self.pending -= 1
        return reply[-1]

    def flush(self) -> None:
        """Collect the replies to every command sent so far."""
        while self.pending:
            reply = self._reply()
            if reply != b"ok":
                raise ViewerError(f"the meshcat server refused a command: {reply[:80].decode('utf-8', 'replace')}")

    def send(self, command):
        data = command.lower()
        self._request(data["type"].encode("utf-8"), data["path"].encode("utf-8"), umsgpack.packb(data))

    def get_scene(self):
        self.flush()
        self._request(b"get_scene")
        return self._reply().decode("utf-8")

    def close(self) -> None:
        self.zmq_socket.close(linger=0)
