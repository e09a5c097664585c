"""The one thread that talks to meshcat.

The simulating thread publishes frames and submits jobs; this thread applies
them in order. Frames that arrive faster than meshcat takes them are
coalesced: of several frames waiting in a row only the newest is applied
(geometry is sent when a node first appears or its looks change, transforms
only when a node moved), so a slow browser or server never slows the episode.
"""

from __future__ import annotations

import atexit
import threading
from concurrent.futures import Future

import meshcat

from bullet_world.viewer.meshcat_objects import MeshcatScene, set_camera
from bullet_world.viewer.scene import Frame
from bullet_world.viewer.server import LocalServer, QuietWindow, ViewerError

_STOP = object()


class MeshcatThread:
    """Owns the live meshcat server and scene; runs every meshcat call of this viewer."""

    def __init__(self, name: str = "teachbot-meshcat"):
        self._items: list = []
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self.server: LocalServer | None = None
        self.scene: MeshcatScene | None = None
        self._window: QuietWindow | None = None
        self.error: str = ""
        self.frames_published = self.frames_applied = 0
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()
        atexit.register(self._stop_server)

    # -- called from the simulating thread ------------------------------------------------
    def publish(self, frame: Frame) -> None:
        """Queue a frame for the live scene (coalesced with frames still waiting)."""
        with self._lock:
            self._items.append(frame)
            self.frames_published += 1
        self._wake.set()

    def submit(self, job) -> Future:
        """Run ``job()`` on the meshcat thread after everything queued so far; returns its future."""
        future: Future = Future()
        with self._lock:
            self._items.append((job, future))
        self._wake.set()
        return future

    def drain(self, timeout_s: float) -> bool:
        """Wait until everything queued so far is applied (meshcat's server has taken it); False if that takes
        longer than ``timeout_s`` (the caller goes on either way)."""
        try:
            self.submit(lambda: None).result(timeout=timeout_s)
        except Exception:  # a timeout, or the thread stopped: nothing to wait for
            return False
        return True

    def start_live(self, camera: tuple, timeout_s: float, reply_timeout_s: float = 10.0) -> str:
        """Start the loopback server and the live scene; returns the page's URL. The server must answer
        each batch of commands within ``reply_timeout_s``, or the live view stops."""
        def start() -> str:
            self.server = LocalServer(timeout_s)
            self._window = QuietWindow(self.server.zmq_url, self.server.web_url, int(reply_timeout_s * 1000))
            visualizer = meshcat.Visualizer(window=self._window)
            set_camera(visualizer, *camera)
            self.scene = MeshcatScene(visualizer)
            return self.server.web_url
        return self.submit(start).result(timeout=timeout_s + 10)

    def stop(self, timeout_s: float = 30.0) -> None:
        """Finish the queue, stop the server and the thread."""
        if self._thread.is_alive():
            with self._lock:
                self._items.append(_STOP)
            self._wake.set()
            self._thread.join(timeout_s)
        self._stop_server()
        atexit.unregister(self._stop_server)

    @property
    def live(self) -> bool:
        return self.scene is not None and not self.error

    # -- the thread ---------------------------------------------------------------
    def _run(self) -> None:
        while True:
            self._wake.wait()
            with self._lock:
                items, self._items = self._items, []
                self._wake.clear()
            for position, item in enumerate(items):
                if item is _STOP:
                    self._fail_waiting(items[position + 1:])
                    return
                if isinstance(item, tuple):
                    self._run_job(*item)
                elif not (position + 1 < len(items) and isinstance(items[position + 1], dict)):
                    self._apply(item)

    def _apply(self, frame: Frame) -> None:
        if not self.live:
            return
        try:
            self.scene.apply(frame)
            self.frames_applied += 1
        except Exception as error:  # the live view stops; the session and any recording go on
            self.error = str(error) if isinstance(error, ViewerError) else f"{type(error).__name__}: {error}"

    @staticmethod
    def _run_job(job, future: Future) -> None:
        if not future.set_running_or_notify_cancel():
            return
        try:
            future.set_result(job())
        except BaseException as error:  # handed to the caller through the future
            future.set_exception(error)

    @staticmethod
    def _fail_waiting(items: list) -> None:
        for item in items:
            if isinstance(item, tuple):
                item[1].set_exception(ViewerError("the viewer was closed"))

    def _stop_server(self) -> None:
        window, self._window = self._window, None
        if window is not None and not self._thread.is_alive():
            window.close()
        server, self.server = self.server, None
        if server is not None:
            server.stop()
