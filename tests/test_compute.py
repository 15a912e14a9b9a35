"""Running a dask stage on an existing dask.distributed cluster given its address."""

from __future__ import annotations

import time

import numpy as np
import pytest
import xarray as xr

from g2tom.cli.main import main
from g2tom.compute import ComputeOptions
from g2tom.stages import oxide
from tests.conftest import SMALL_ARGS

distributed = pytest.importorskip("distributed")


def test_scheduler_address_runs_the_same_stage(tmp_path, small) -> None:
    expected = oxide.build(small, ComputeOptions(progress=False))
    overrides = list(SMALL_ARGS)
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


def test_compute_pins_blas_to_one_thread_for_any_caller() -> None:
    """A notebook calling a stage gets the CLI's one BLAS thread per dask thread."""
    import dask
    from threadpoolctl import threadpool_info, threadpool_limits

    from g2tom.compute import compute

    def blas_threads() -> list[int]:
        return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]

    with threadpool_limits(limits=2, user_api="blas"):  # as a notebook without the CLI's pins
        if not blas_threads() or max(blas_threads()) < 2:
            pytest.skip("this BLAS cannot run two threads")
        (inside,) = compute(dask.delayed(blas_threads)(), options=ComputeOptions(progress=False))
        assert inside and set(inside) == {1}
        assert max(blas_threads()) == 2  # restored for the caller afterwards


def test_progress_bar_stays_out_of_logs(monkeypatch, capfd) -> None:
    """Not a terminal: no progress bar, so no carriage returns in a log."""
    import dask
    import time

    from g2tom import compute as compute_module

    monkeypatch.setattr(compute_module, "PROGRESS_AFTER", 0.0)
    compute_module.compute(dask.delayed(time.sleep)(0.6), options=ComputeOptions(progress=True))
    out, err = capfd.readouterr()
    assert "\r" not in out + err and "[#" not in out + err


def test_multi_process_cluster_gives_identical_cube(tmp_path, small, cluster_address) -> None:
    """Two worker processes (as `dask scheduler` + `dask worker` would give: conftest's cluster)
    reproduce the local cube."""
    from g2tom.stages import contact, cube

    quiet = ComputeOptions(progress=False)
    expected = cube.build(small, contact.build(small), oxide.build(small, quiet), quiet)
    overrides = list(SMALL_ARGS)
    for stage in ("contact", "oxide", "cube"):
        assert main([stage, "--data-dir", str(tmp_path), "--scheduler", cluster_address,
                     "--no-progress", *overrides]) == 0
    with xr.open_dataset(tmp_path / "cube.nc") as ds:
        for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
            np.testing.assert_array_equal(ds[name].values, expected[name].values)
        assert ds.attrs["contact.window"] == small.contact.window  # the resolved value, recorded


#: What the tasks of the next test did, in order (a thread cluster: they run in this process).
_LOG: list[tuple[str, str]] = []


def _held(name: str, seconds: dict[str, float]) -> str:
    """A task that records when it starts and ends."""
    _LOG.append(("start", name))
    time.sleep(seconds[name])
    _LOG.append(("end", name))
    return name


def test_tasks_start_in_the_given_order_one_per_thread() -> None:
    """The atlas's scenes longest first: each starts only when a thread is free, in the list's order
    (submitted at once, the scheduler would queue them on the workers in turn, and a long one could
    wait behind another long one while the other worker runs short ones)."""
    from g2tom.compute import in_turn

    seconds = {"long": 0.6, "long2": 0.5, "mid": 0.3, "short": 0.05, "short2": 0.05, "short3": 0.05}
    _LOG.clear()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        done = list(in_turn(client, _held, list(seconds), lambda name: f"held-{name}", seconds))
    starts = [name for event, name in _LOG if event == "start"]
    assert starts == list(seconds) and sorted(done) == sorted(seconds)
    running = peak = 0
    for event, _ in _LOG:
        running += 1 if event == "start" else -1
        peak = max(peak, running)
    assert peak == 2  # both threads busy, never more
    # "mid" starts when "long2" ends (the first thread free), not before
    assert _LOG.index(("start", "mid")) > _LOG.index(("end", "long2"))


def test_a_cluster_interrupted_while_it_starts_is_closed_and_not_left_to_close_at_exit(monkeypatch) -> None:
    """SIGTERM (or Ctrl-C taken by the main thread) while the local cluster starts: the cluster is
    closed as far as it goes and taken off distributed's exit-time closing, which printed a traceback
    after the command's one line when the workers were still starting."""
    distributed = pytest.importorskip("distributed")
    from contextlib import ExitStack

    from distributed.core import Status

    import g2tom.compute as compute_module

    started = []

    class InterruptedWhileStarting(distributed.LocalCluster):
        def __init__(self, *args, **kwargs) -> None:  # noqa: ANN002, ANN003
            started.append(self)
            super().__init__(*args, **kwargs)
            raise KeyboardInterrupt

    monkeypatch.setattr(distributed, "LocalCluster", InterruptedWhileStarting)
    with pytest.raises(KeyboardInterrupt), ExitStack() as stack:
        compute_module._client(stack, compute_module.ComputeOptions(workers=2, progress=False))
    assert len(started) == 1
    assert not started[0].shutdown_on_close and started[0].status == Status.closed
