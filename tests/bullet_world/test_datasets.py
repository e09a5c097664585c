"""Task data sets: disjoint stratified pools, cached as NPZ + JSON, rebuilt when the generator changes."""

import json

import numpy as np
import pytest

from bullet_world.catalogue import DatasetPlan
from bullet_world.datasets import generator_hash, load_datasets

PLAN = DatasetPlan(pools=2, pool_size=12, test_size=8, objects_per_scene=8)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="module")
def datasets(cache):
    return load_datasets("pack-lunchbox", plan=PLAN, cache=cache)


def test_pools_are_stratified_and_disjoint(datasets):
    assert [len(pool) for pool in datasets.train] == [12, 12] and len(datasets.test) == 8
    for pool in (*datasets.train, datasets.test):
        _, counts = np.unique(pool.concepts, return_counts=True)
        assert counts.max() - counts.min() <= 1
        assert pool.X.shape[1] == len(datasets.feature_names)
    rows = np.vstack([pool.X for pool in (*datasets.train, datasets.test)])
    assert len(np.unique(rows, axis=0)) == len(rows)  # no observation appears twice


def test_the_cache_holds_npz_and_json_and_is_reused(cache, datasets):
    files = sorted(p.name for p in (cache / "datasets").iterdir())
    assert [name.rsplit(".", 1)[1] for name in files] == ["json", "npz"]
    metadata = json.loads((cache / "datasets" / files[0]).read_text())
    assert metadata["task"] == "pack-lunchbox" and metadata["plan"]["pool_size"] == 12
    again = load_datasets("pack-lunchbox", plan=PLAN, cache=cache)
    assert np.array_equal(again.test.X, datasets.test.X) and again.metadata["generator"] == metadata["generator"]
    assert list(again.test.kinds) == list(datasets.test.kinds)


def test_the_key_changes_with_the_request():
    key = generator_hash("pack-lunchbox", "kitchen-1", PLAN, 0, False)
    assert key != generator_hash("pack-lunchbox", "kitchen-1", PLAN, 1, False)
    assert key != generator_hash("pack-lunchbox", "kitchen-2", PLAN, 0, False)
    assert key != generator_hash("pack-lunchbox", "kitchen-1", PLAN, 0, True)


def test_an_unreadable_cache_file_is_rebuilt(tmp_path):
    plan = DatasetPlan(pools=1, pool_size=4, test_size=4, objects_per_scene=4)
    first = load_datasets("pack-lunchbox", plan=plan, cache=tmp_path)
    npz = next((tmp_path / "datasets").glob("*.npz"))
    npz.write_bytes(b"not an npz file")
    messages = []
    again = load_datasets("pack-lunchbox", plan=plan, cache=tmp_path, progress=messages.append)
    assert np.array_equal(again.test.X, first.test.X) and "unreadable" in messages[0]


BUILD_ONE = """
import sys
from bullet_world.catalogue import DatasetPlan
from bullet_world.datasets import load_datasets
plan = DatasetPlan(pools=1, pool_size=4, test_size=4, objects_per_scene=4)
built = []
load_datasets("pack-lunchbox", plan=plan, cache=sys.argv[1], progress=built.append)
print(len(built))
"""


def test_two_processes_needing_the_same_data_set_build_it_once(tmp_path):
    """Test workers and parallel runs share the cache: the second waits for the first's file instead of
    rendering the same scenes again."""
    import subprocess
    import sys

    runs = [subprocess.Popen([sys.executable, "-c", BUILD_ONE, str(tmp_path)], stdout=subprocess.PIPE, text=True)
            for _ in range(2)]
    messages = sorted(int(run.communicate(timeout=300)[0].strip()) for run in runs)
    assert messages[0] == 0 and messages[1] > 0  # one built (and said so), the other only read
    assert len(list((tmp_path / "datasets").glob("*.npz"))) == 1
