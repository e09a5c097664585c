"""Issue 43 item 4: a suite on a real two-node Ray cluster (loopback, token authentication) writes the same tables
and transcripts, byte for byte, as a local run with one worker."""

import csv
import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.dialog.test_ray_settings import listening_sockets
from tests.dialog.test_regress import write_suite

ROOT = Path(__file__).resolve().parents[2]
LOOPBACK = ("127.0.0.1:", "[::ffff:127.0.0.1]:", "[::1]:")


def regress(suite: Path, results: Path, *options: str, environment: dict | None = None):
    return subprocess.run([sys.executable, "-m", "dialog.cli", "regress", "--suite", str(suite), "--results",
                           str(results), "--no-progress", *options], cwd=ROOT, capture_output=True, text=True,
                          env=os.environ | (environment or {}), timeout=900)


def tables(results: Path) -> dict[str, bytes]:
    """Every table and transcript a run wrote, as bytes; from episodes.csv the wall-time column is left out
    (it is the one thing two runs of the same episodes cannot share)."""
    found = {str(path.relative_to(results)): path.read_bytes() for pattern in ("episodes/**/*.csv",
                                                                                "transcripts/**/*.jsonl",
                                                                                "*.csv")
             for path in sorted(results.glob(pattern)) if path.name != "episodes.csv"}
    rows = list(csv.reader(io.StringIO((results / "episodes.csv").read_text())))
    seconds = rows[0].index("seconds")
    found["episodes.csv without seconds"] = repr([row[:seconds] + row[seconds + 1:] for row in rows]).encode()
    return found


def test_a_suite_on_a_two_node_loopback_cluster_matches_a_local_run(tmp_path):
    pytest.importorskip("ray", reason="the optional Ray extra is not installed: pip install 'teachbot[ray]'")
    from dialog.experiments.ray_cluster import _running, loopback_cluster

    suite = write_suite(tmp_path)
    local = regress(suite, tmp_path / "local", "--workers", "1")
    assert local.returncode == 0, local.stderr
    with loopback_cluster(nodes=2, cpus=1) as cluster:
        assert len(cluster.nodes) == 2 and cluster.address.startswith("127.0.0.1:")
        on_ray = regress(suite, tmp_path / "ray", "--ray", cluster.address, environment=cluster.environment)
        assert on_ray.returncode == 0, on_ray.stderr
        assert "runs on that cluster" in on_ray.stderr  # a named cluster is announced
        if subprocess.run(["ss", "-V"], capture_output=True).returncode == 0:
            sockets = listening_sockets(cluster.pids())
            assert sockets and all(address.startswith(LOOPBACK) for address, _ in sockets), sockets
        joined = cluster.pids_of(1)
        assert any(b"raylet" in name for name in joined.values()), joined  # the second node is a node of its own
        seen = cluster.pids()
    assert [pid for pid in seen if _running(pid)] == []  # every process of the cluster has ended
    local_tables, ray_tables = tables(tmp_path / "local"), tables(tmp_path / "ray")
    assert len(local_tables) > 8 and local_tables.keys() == ray_tables.keys()
    assert [name for name in local_tables if local_tables[name] != ray_tables[name]] == []


def test_an_episode_on_a_node_sends_its_transcript_back_instead_of_writing_the_driver_s_path(tmp_path):
    """On a real cluster the driver's results folder is not on the node: the transcript comes back as bytes."""
    from dialog.experiments.episodes import run_episode
    from dialog.experiments.runner import episode_on_node, episode_specs
    from dialog.experiments.suite import load_suite

    spec = episode_specs(load_suite(write_suite(tmp_path)), tmp_path / "driver")[0]
    result, transcript = episode_on_node(spec)
    assert not (tmp_path / "driver").exists()  # nothing written where the driver keeps its results
    assert result["spec"]["transcript"] == spec.transcript
    local = run_episode(spec)
    assert transcript == Path(spec.transcript).read_bytes() and result["series"] == local["series"]
