"""``regress --ray``: a local instance on 127.0.0.1 with token authentication; a named cluster is announced."""

import os
import re
import signal
import subprocess
import sys
import types

import pytest

from dialog.experiments import runner
from dialog.experiments.ray_cluster import descendants


class FakeRay:
    """Records how ray.init was called and what the environment held at that moment."""

    def __init__(self):
        self.calls = []
        self._private = types.SimpleNamespace(ray_constants=types.SimpleNamespace(ENABLE_RAY_CLUSTER=True))
        self.__version__ = "2.60.0"
        modes = types.SimpleNamespace(TOKEN=1, DISABLED=0)
        self._raylet = types.SimpleNamespace(AuthenticationMode=modes, get_authentication_mode=lambda: self.mode,
                                             Config=types.SimpleNamespace(initialize=self._reload))
        self.mode = 0

    def _reload(self, _config):
        self.mode = 1 if os.environ.get("RAY_AUTH_MODE") == "token" else 0

    def shutdown(self):
        self.calls.clear()

    def is_initialized(self):
        return bool(self.calls)

    def init(self, **options):
        self.calls.append({"options": options, "auth": os.environ.get("RAY_AUTH_MODE"),
                           "clusters": os.environ.get("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"),
                           "flag": self._private.ray_constants.ENABLE_RAY_CLUSTER})
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(15))  # what ray.init does

    def remote(self, function):
        return function


def test_local_ray_starts_on_loopback_with_tokens_and_puts_things_back(monkeypatch, capsys):
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")
    monkeypatch.delenv("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", raising=False)
    handler = signal.getsignal(signal.SIGTERM)
    ray = FakeRay()
    runner.start_local_ray(ray)
    runner.start_local_ray(ray)  # already running: nothing more
    assert len(ray.calls) == 1
    call = ray.calls[0]
    assert call["auth"] == "token" and call["clusters"] == "0" and call["flag"] is False
    assert call["options"]["include_dashboard"] is False and "address" not in call["options"]
    assert "RAY_AUTH_MODE=disabled ignored" in capsys.readouterr().err
    assert "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER" not in os.environ and ray._private.ray_constants.ENABLE_RAY_CLUSTER
    assert signal.getsignal(signal.SIGTERM) is handler


def test_a_named_cluster_is_announced_as_trusted_with_code_and_pickles(monkeypatch, capsys):
    fake = FakeRay()
    monkeypatch.setitem(sys.modules, "ray", fake)
    assert runner.run_on_ray([], "ray://cluster.example:10001", progress=False) == []
    err = capsys.readouterr().err
    assert "runs on that cluster" in err and "unpickled" in err and "trust" in err
    assert fake.calls[0]["options"]["address"] == "ray://cluster.example:10001"


def listening_sockets(pids: set[int]) -> list[tuple[str, str]]:
    """(local address, process name) of every listening TCP socket the processes own (``ss -ltnp``)."""
    table = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=True).stdout
    sockets = []
    for line in table.splitlines():
        owners = {int(pid) for pid in re.findall(r"pid=(\d+)", line)}
        if owners & pids:
            sockets.append((line.split()[3], re.findall(r'\("([^"]+)"', line)[0]))
    return sockets


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc and runs ss")
def test_a_local_ray_instance_listens_on_loopback_only():
    ray = pytest.importorskip("ray", reason="the optional Ray extra is not installed")
    if subprocess.run(["ss", "-V"], capture_output=True).returncode != 0:
        pytest.skip("ss (iproute2) is not installed")
    if ray.is_initialized():
        ray.shutdown()
    try:
        runner.start_local_ray(ray)
    except Exception as error:  # no room for Ray here (shared memory, ports): nothing to measure
        pytest.skip(f"Ray could not start: {type(error).__name__}: {error}")
    try:
        from ray._raylet import AuthenticationMode, get_authentication_mode

        assert get_authentication_mode() == AuthenticationMode.TOKEN
        assert ray.get(ray.remote(lambda: 41 + 1).remote()) == 42  # a worker is up and listening too
        sockets = listening_sockets(descendants({os.getpid()}))
        names = {name for _, name in sockets}
        assert {"gcs_server", "raylet"} <= names, sockets
        loopback = ("127.0.0.1:", "[::ffff:127.0.0.1]:", "[::1]:")
        assert all(address.startswith(loopback) for address, _ in sockets), sockets
    finally:
        ray.shutdown()


def test_a_ray_without_token_authentication_is_refused(monkeypatch):
    ray = FakeRay()
    ray._raylet.Config.initialize = lambda _config: None  # this Ray never turns tokens on
    monkeypatch.delenv("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", raising=False)
    with pytest.raises(RuntimeError, match="token authentication"):
        runner.start_local_ray(ray)
    assert not ray.is_initialized()
