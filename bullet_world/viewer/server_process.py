"""The meshcat server of the viewer, run as a child process: web page and ZeroMQ on 127.0.0.1 only.

meshcat's own server binds its ZeroMQ socket to 127.0.0.1 but lets tornado
serve the web page on every interface; here tornado listens on the loopback
address too. Run as a script (``python server_process.py``), it prints
``zmq_url=...`` and ``web_url=...`` for the parent and serves until stopped.
It imports only tornado, ZeroMQ and meshcat's server module: meshcat's package
``__init__`` (numpy, IPython, PIL) is skipped, which halves the start-up time.

The server ends with its parent, however the parent ends: on Linux the kernel
sends it SIGTERM when the parent dies (``prctl(PR_SET_PDEATHSIG)``; strictly,
when the parent's thread that started it ends), and everywhere it exits when
its standard input, a pipe the parent holds open, reaches end of file. Ctrl-C
in the terminal is left to the parent, which stops the server itself.
"""

import ctypes
import importlib.util
import os
import signal
import sys
import threading
import types

LOOPBACK = "127.0.0.1"
PR_SET_PDEATHSIG = 1


def follow_parent(parent_pid: int) -> None:
    """End this process when the parent ``parent_pid`` ends (death signal, plus end of file on stdin)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
        except (OSError, AttributeError):
            pass  # the stdin watch below still ends the server
    if os.getppid() != parent_pid:  # the parent ended before the death signal was armed
        os._exit(0)
    threading.Thread(target=_exit_at_end_of_input, name="parent-watch", daemon=True).start()


def _exit_at_end_of_input() -> None:
    while sys.stdin.buffer.read(4096):
        pass
    os._exit(0)


def _server_module():
    """meshcat.servers.zmqserver without running meshcat/__init__.py (the server needs none of it)."""
    if "meshcat" not in sys.modules:
        spec = importlib.util.find_spec("meshcat")
        package = types.ModuleType("meshcat")
        package.__path__ = list(spec.submodule_search_locations)
        sys.modules["meshcat"] = package
    import meshcat.servers.zmqserver as server

    return server


def bridge_class():
    import tornado.web

    server = _server_module()

    class LoopbackApplication(tornado.web.Application):
        def listen(self, port, address="", **kwargs):  # the address is forced to the loopback one
            return super().listen(port, address=LOOPBACK, **kwargs)

    class LoopbackBridge(server.ZMQWebSocketBridge):
        def make_app(self):
            return LoopbackApplication([
                (r"/static/(.*)", server.StaticFileHandlerNoCache,
                 {"path": server.VIEWER_ROOT, "default_filename": "index.html"}),
                (r"/", server.WebSocketHandler, {"bridge": self}),
            ])

    return LoopbackBridge


def main() -> None:
    if len(sys.argv) > 2 and sys.argv[1] == "--parent":
        follow_parent(int(sys.argv[2]))
    bridge = bridge_class()(host=LOOPBACK)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
