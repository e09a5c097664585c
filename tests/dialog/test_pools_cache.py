"""The in-memory cache of pools: one data set file serves every count of training pools up to the plan's."""

from dialog.experiments import pools


def test_a_sweep_over_data_sets_loads_the_file_once(monkeypatch):
    loads = []

    def counted(task, kitchen, datasets, plan_options, data_seed, progress):
        loads.append(datasets)
        return pools.PoolSet(tuple(f"pool {i}" for i in range(datasets)), "test pool", task)

    monkeypatch.setattr(pools, "_load_pools", counted)
    monkeypatch.setattr(pools, "_loaded", {})
    planned = pools.load_task("pack-lunchbox").datasets.pools
    for datasets in range(1, planned + 1):
        loaded = pools.load_pools("pack-lunchbox", "kitchen-1", datasets)
        assert loaded.train == tuple(f"pool {i}" for i in range(datasets)) and loaded.test == "test pool"
    assert loads == [planned]  # the plan's file, loaded once
    pools.load_pools("pack-lunchbox", "kitchen-1", planned + 2)  # more pools than the plan: another file
    assert loads == [planned, planned + 2]
