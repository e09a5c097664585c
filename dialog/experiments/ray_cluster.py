"""A Ray cluster of several nodes on this machine's loopback address, with token authentication.

``tests/dialog/test_ray_cluster.py`` runs a suite on it with ``regress --ray ADDRESS`` and
``scripts/bench_ray.py`` measures what a cluster costs per episode against local workers. Each node is
a ``ray start --block`` process of its own (the head, then nodes joining it, each with its own CPUs), in
its own process group, listening on 127.0.0.1 only and on free ports; every process of the cluster is
ended by its id when the ``with`` block ends, however it ends (never ``ray stop``, which would end every
Ray process of the user on the machine). docs/experiments.md says how to do the same on real machines.
"""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from learning.errors import SetupError

LOOPBACK = "127.0.0.1"
STARTUP_SECONDS = 180.0  # a loaded two-core machine takes a while to start a Ray node


NODE_ATTEMPTS = 5  # Ray gives a raylet 30 s to register; a loaded machine can miss that more than once


class NodeDied(SetupError):
    """A node of the loopback cluster (``index``: 0 the head) ended while the cluster was starting."""

    def __init__(self, index: int, message: str):
        super().__init__(message)
        self.index = index


def free_port() -> int:
    """A TCP port free on the loopback address now."""
    with socket.socket() as probe:
        probe.bind((LOOPBACK, 0))
        return probe.getsockname()[1]


@dataclass
class LoopbackCluster:
    """A running cluster: its GCS ``address``, the environment a driver needs (the token), its nodes."""

    address: str
    environment: dict[str, str]
    nodes: list[subprocess.Popen] = field(default_factory=list)
    folder: Path = Path()

    def pids(self) -> set[int]:
        """Every running process of the cluster (the nodes and all they started)."""
        return descendants({node.pid for node in self.nodes if node.poll() is None})

    def pids_of(self, index: int) -> dict[int, bytes]:
        """The running processes of node ``index`` (its ``ray start`` and all it started), with their names."""
        node = self.nodes[index]
        return {pid: _name(pid) for pid in descendants({node.pid} if node.poll() is None else set())}


def token_environment(token: str) -> dict[str, str]:
    """What every node and driver of the cluster needs in its environment: token mode and the token, and
    (this machine being the whole cluster) its loopback address taken as the machine's address."""
    return {"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": token, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}


@contextmanager
def loopback_cluster(nodes: int = 2, cpus: int = 1) -> Iterator[LoopbackCluster]:
    """Start a head and ``nodes - 1`` joining nodes, ``cpus`` CPUs each, on 127.0.0.1 with a fresh token."""
    if shutil.which("ray", path=str(Path(sys.executable).parent)) is None:
        raise SetupError("the ray command is not installed: pip install 'teachbot[ray]'")
    environment = token_environment(secrets.token_hex(32))
    folder = Path(tempfile.mkdtemp(prefix="tbray-", dir="/tmp"))  # short: Ray's socket paths have a length limit
    port = free_port()
    cluster = LoopbackCluster(f"{LOOPBACK}:{port}", environment, folder=folder)
    head = ["--head", f"--port={port}", f"--temp-dir={folder}", "--include-dashboard=false"]
    try:
        for index in range(nodes):
            _add_node(cluster, head if index == 0 else [f"--address={cluster.address}"], cpus)
        yield cluster
    finally:
        stop_cluster(cluster)
        shutil.rmtree(folder, ignore_errors=True)


def _add_node(cluster: LoopbackCluster, options: list[str], cpus: int, attempts: int = NODE_ATTEMPTS) -> None:
    """Start one node and wait until the cluster counts it; a node that gave up starting is started again
    (Ray gives a raylet 30 s to register, which a loaded machine can miss)."""
    index = len(cluster.nodes)
    for attempt in range(1, attempts + 1):
        cluster.nodes.append(_start_node(options, cpus, cluster.environment, cluster.folder, index))
        try:
            _wait_for_nodes(cluster, index + 1)
            return
        except NodeDied as died:
            if died.index != index:
                raise  # a node that was up has gone: starting this one again would not help
            failed = cluster.nodes.pop()
            _signal_group(failed.pid, signal.SIGKILL)
            if attempt == attempts:
                raise


def _start_node(options: list[str], cpus: int, environment: dict, folder: Path,
                index: int) -> subprocess.Popen:
    ports = {name: free_port() for name in ("node-manager-port", "object-manager-port", "metrics-export-port",
                                            "dashboard-agent-listen-port", "dashboard-agent-grpc-port",
                                            "runtime-env-agent-port")}
    command = [sys.executable, "-m", "dialog.experiments.ray_cluster", "start", "--block", *options,
               f"--node-ip-address={LOOPBACK}", f"--num-cpus={cpus}",
               "--num-gpus=0", "--disable-usage-stats", *(f"--{name}={value}" for name, value in ports.items())]
    with open(folder / f"node-{index}.log", "ab") as log:  # the node keeps its own copy of the descriptor
        return subprocess.Popen(command, env=os.environ | environment, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)


def _wait_for_nodes(cluster: LoopbackCluster, count: int) -> None:
    """Until the cluster has ``count`` nodes alive (``ray status`` through the token), or a node died."""
    ray = shutil.which("ray", path=str(Path(sys.executable).parent)) or "ray"
    deadline = time.monotonic() + STARTUP_SECONDS
    while time.monotonic() < deadline:
        for index, node in enumerate(cluster.nodes):
            if node.poll() is not None:
                raise NodeDied(index, f"Ray node {index} ended with code {node.returncode} while starting: "
                                 f"{_tail(cluster.folder / f'node-{index}.log')}")
        try:
            status = subprocess.run([ray, "status", f"--address={cluster.address}"], capture_output=True,
                                    text=True, env=os.environ | cluster.environment, timeout=60)
        except subprocess.TimeoutExpired:
            continue  # a loaded machine: ask again
        if status.returncode == 0 and status.stdout.count("node_") >= count:
            return
        time.sleep(1.0)
    raise SetupError(f"the loopback Ray cluster did not reach {count} nodes in {STARTUP_SECONDS:.0f} s")


def stop_cluster(cluster: LoopbackCluster, grace: float = 30.0) -> None:
    """End every process of the cluster by its id: SIGTERM to each node's process group, SIGKILL after
    ``grace`` seconds to whatever is left (workers a raylet started in a group of their own included)."""
    pids = cluster.pids()
    for node in cluster.nodes:
        _signal_group(node.pid, signal.SIGTERM)
    deadline = time.monotonic() + grace
    for node in cluster.nodes:
        try:
            node.wait(timeout=max(deadline - time.monotonic(), 0.1))
        except subprocess.TimeoutExpired:
            pass
    pids |= cluster.pids()
    for node in cluster.nodes:
        _signal_group(node.pid, signal.SIGKILL)
        node.wait()
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    deadline = time.monotonic() + 10.0
    while any(_running(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.1)  # SIGKILL is delivered, not yet done


def _signal_group(pid: int, signum: int) -> None:
    try:
        os.killpg(pid, signum)  # each node was started in a session (and process group) of its own
    except (ProcessLookupError, PermissionError):
        pass


def descendants(roots: set[int]) -> set[int]:
    """``roots`` and every process below them (read from /proc)."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parents[int(entry.name)] = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
    found, grown = set(roots), True
    while grown:
        new = {pid for pid, parent in parents.items() if parent in found} - found
        found |= new
        grown = bool(new)
    return found


def _running(pid: int) -> bool:
    """The process exists and is not a zombie (its parent not having read its exit yet)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def _name(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/comm").read_bytes().strip()
    except OSError:
        return b""


def _tail(path: Path, lines: int = 5) -> str:
    try:
        return " | ".join(path.read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return "(no log)"


def start_loopback_node(argv: list[str]) -> int:
    """``ray start ARGV`` for a node of a cluster on the loopback address (``python -m`` this module).

    Ray takes 127.0.0.1 for this machine's address only with clusters turned off
    (``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0``, inherited by every process the node starts), and then refuses
    to join one; with clusters on it replaces 127.0.0.1 by the machine's network address and listens on
    every interface. So the ``ray start`` here is allowed to join, and keeps 127.0.0.1 as given.
    """
    os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    from ray._private import ray_constants, services
    from ray.scripts.scripts import main

    ray_constants.ENABLE_RAY_CLUSTER = True
    services.resolve_ip_for_localhost = lambda host: host
    sys.argv = ["ray", *argv]
    return main()


if __name__ == "__main__":
    sys.exit(start_loopback_node(sys.argv[1:]))
