"""What a Ray cluster costs per episode against local worker processes, on the same episodes and cores.

Plays a suite's episodes (as ``teachbot regress`` does) with ``--workers N`` local processes, then on a Ray
cluster of N one-CPU nodes started on this machine's loopback address with token authentication
(``dialog/experiments/ray_cluster.py``: a head and nodes joining it, as on real machines), in rotating
order, ``--repeats`` times each, on half the episodes and on all of them. The first Ray round is reported
apart (the nodes start their worker processes and import the project). A line through the two sizes (medians)
splits each way's wall time into a fixed part (local: starting the worker processes, which load the data
sets; Ray: dispatch) and a part per episode; the overhead per episode is Ray's part per episode minus the
local one. On a machine shared with other work, wall time also depends on the scheduler's shares (with
the kernel's autogroup, each Ray node in its own session gets a share of its own, the local workers share
this script's), so the CPU time is measured too: the episodes' own, and all the rest this process, its
local workers and every process of the cluster spent during the round (``overhead``).

    python scripts/bench_ray.py --suite smoke --json        # last line: one JSON object
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from dialog.experiments.pools import load_pools
from dialog.experiments.ray_cluster import loopback_cluster
from dialog.experiments.runner import episode_specs, run_locally, run_on_ray
from dialog.experiments.suite import load_suite
from learning.errors import TeachbotError

TICKS = os.sysconf("SC_CLK_TCK")


def process_cpu(pids: set[int]) -> float:
    """CPU seconds the running processes ``pids`` have used so far (user + system, from /proc)."""
    total = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += int(fields[11]) + int(fields[12])
    return total / TICKS


def machine_cpu(cluster) -> float:
    """CPU seconds of this process, its finished children (local workers) and the processes of ``cluster``
    (None: a local round, which the idle cluster's housekeeping is not charged to)."""
    times = os.times()
    own = times.user + times.system + times.children_user + times.children_system
    return own + (0.0 if cluster is None else process_cpu(cluster.pids()))


def timed(cluster, run, *arguments, **options) -> dict:
    """Wall time, the episodes' own CPU time, and the CPU time everything around them took (``overhead``)."""
    began, cpu = time.perf_counter(), machine_cpu(cluster)
    results = run(*arguments, **options)
    episodes = sum(r["cpu_seconds"] for r in results)
    return {"seconds": time.perf_counter() - began, "cpu_seconds": episodes,
            "overhead_cpu": machine_cpu(cluster) - cpu - episodes}


def per_episode(small: float, large: float, n_small: int, n_large: int) -> tuple[float, float]:
    """(fixed seconds, seconds per episode) of the line through two runs of n_small and n_large episodes."""
    slope = (large - small) / (n_large - n_small)
    return small - slope * n_small, slope


def measure(suite_name: str, nodes: int, repeats: int, folder: Path) -> dict:
    suite = load_suite(suite_name)
    load_pools(suite.task, suite.kitchen, suite.datasets, suite.plan_options, data_seed=suite.data_seed)
    specs = episode_specs(suite, folder)
    half = specs[: len(specs) // 2]
    rounds: dict[str, list[dict]] = {"local half": [], "local all": [], "ray half": [], "ray all": []}
    with loopback_cluster(nodes=nodes, cpus=1) as cluster:
        os.environ.update(cluster.environment)  # before ray is imported: this driver speaks with the token
        cold = timed(cluster, run_on_ray, specs, cluster.address, progress=False)
        for _ in range(repeats):  # rotating order, so that a change of load falls on all four alike
            for name, chosen in (("half", half), ("all", specs)):
                rounds[f"local {name}"].append(timed(None, run_locally, chosen, workers=nodes, progress=False))
                rounds[f"ray {name}"].append(timed(cluster, run_on_ray, chosen, cluster.address, progress=False))
        import ray

        ray.shutdown()
    wall = {name: statistics.median(r["seconds"] for r in runs) for name, runs in rounds.items()}
    local_fixed, local_each = per_episode(wall["local half"], wall["local all"], len(half), len(specs))
    ray_fixed, ray_each = per_episode(wall["ray half"], wall["ray all"], len(half), len(specs))
    return {"suite": suite.name, "episodes": len(specs), "half": len(half), "nodes": nodes, "workers": nodes,
            "repeats": repeats, "cores": os.cpu_count(), "load_average": round(os.getloadavg()[0], 2),
            "seconds": {name: [round(r["seconds"], 2) for r in runs] for name, runs in rounds.items()},
            "ray_cold_seconds": round(cold["seconds"], 2),
            "local_fixed_s": round(local_fixed, 2), "local_ms_per_episode": round(1000 * local_each, 1),
            "ray_fixed_s": round(ray_fixed, 2), "ray_ms_per_episode": round(1000 * ray_each, 1),
            "overhead_ms_per_episode": round(1000 * (ray_each - local_each), 1),
            "cpu_seconds": {name: round(statistics.median(r["cpu_seconds"] for r in runs), 2)
                            for name, runs in rounds.items()},
            "overhead_cpu_seconds": {name: round(statistics.median(r["overhead_cpu"] for r in runs), 2)
                                     for name, runs in rounds.items()},
            "local_overhead_cpu_ms_per_episode": round(1000 * statistics.median(
                r["overhead_cpu"] for r in rounds["local all"]) / len(specs), 1),
            "ray_overhead_cpu_ms_per_episode": round(1000 * statistics.median(
                r["overhead_cpu"] for r in rounds["ray all"]) / len(specs), 1)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--suite", default="smoke", help="the suite whose episodes are played (default smoke)")
    parser.add_argument("--nodes", type=int, default=2, help="Ray nodes of one CPU each = local workers (default 2)")
    parser.add_argument("--repeats", type=int, default=3, help="warm rounds of each (default 3)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if args.nodes < 1 or args.repeats < 1:
        print("bench_ray: --nodes and --repeats are whole numbers >= 1", file=sys.stderr)
        return 2
    try:
        with tempfile.TemporaryDirectory(prefix="bench-ray-") as folder:
            figures = measure(args.suite, args.nodes, args.repeats, Path(folder))
    except TeachbotError as error:
        print(f"bench_ray: {error}", file=sys.stderr)
        return 2
    print(f"{figures['half']} and {figures['episodes']} episodes of {figures['suite']}, {figures['nodes']} local "
          f"workers against {figures['nodes']} one-CPU Ray nodes on 127.0.0.1 ({figures['repeats']} rounds each, "
          f"medians, load average {figures['load_average']} on {figures['cores']} cores):")
    print(f"  local: {figures['local_fixed_s']} s fixed + {figures['local_ms_per_episode']} ms per episode; "
          f"Ray (nodes already up): {figures['ray_fixed_s']} s + {figures['ray_ms_per_episode']} ms per episode")
    print(f"  Ray's overhead per episode: {figures['overhead_ms_per_episode']} ms; the first Ray round on the new "
          f"cluster took {figures['ray_cold_seconds']} s for all {figures['episodes']} episodes")
    print(f"  the episodes' CPU time (s, medians): {figures['cpu_seconds']}")
    print(f"  CPU time around the episodes (this process, local workers, the cluster's processes) per episode: "
          f"local {figures['local_overhead_cpu_ms_per_episode']} ms, Ray {figures['ray_overhead_cpu_ms_per_episode']}"
          " ms")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
