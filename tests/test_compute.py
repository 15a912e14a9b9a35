"""Running a dask stage on an existing dask.distributed cluster given its address."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.cli import main
from pipeline.compute import ComputeOptions
from pipeline.stages import oxide
from tests.conftest import SMALL_OVERRIDES

distributed = pytest.importorskip("distributed")


def test_scheduler_address_runs_the_same_stage(tmp_path, small) -> None:
    expected = oxide.build(small, ComputeOptions(progress=False))
    overrides = [arg for k, v in SMALL_OVERRIDES.items() for arg in ("--set", f"{k}={v}")]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client, distributed.get_task_stream(client) as stream:
            status = main(["oxide", "--data-dir", str(tmp_path), "--scheduler", cluster.scheduler_address,
                           *overrides])
        assert status == 0
        # the work ran on the cluster, not on local threads
        assert any("psi_block" in str(task["key"]) for task in stream.data)
    with xr.open_dataset(tmp_path / "oxide.nc") as ds:
        np.testing.assert_array_equal(ds["psi"].values, expected["psi"].values)
        np.testing.assert_array_equal(ds["threshold"].values, expected["threshold"].values)


def test_multi_process_cluster_gives_identical_cube(tmp_path, small) -> None:
    """Two worker processes (as `dask scheduler` + `dask worker` would give) reproduce the local cube."""
    from pipeline.stages import contact, cube

    quiet = ComputeOptions(progress=False)
    expected = cube.build(small, contact.build(small), oxide.build(small, quiet), quiet)
    overrides = [arg for k, v in SMALL_OVERRIDES.items() for arg in ("--set", f"{k}={v}")]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        for stage in ("contact", "oxide", "cube"):
            assert main([stage, "--data-dir", str(tmp_path), "--scheduler", cluster.scheduler_address,
                         "--no-progress", *overrides]) == 0
    with xr.open_dataset(tmp_path / "cube.nc") as ds:
        for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
            np.testing.assert_array_equal(ds[name].values, expected[name].values)
        assert ds.attrs["contact.window"] == small.contact.window  # the resolved value, recorded
