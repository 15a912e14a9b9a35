"""Where dask work runs: the local threaded scheduler, a local cluster, or a remote one."""

from __future__ import annotations

import os
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from typing import Iterator

import dask

__all__ = ["ComputeOptions", "dask_context"]


@dataclass(frozen=True)
class ComputeOptions:
    """How a stage computes.

    Attributes
    ----------
    scheduler
        Address of an existing ``dask.distributed`` scheduler, or None for local threads.
    workers
        Local worker count: a local ``dask.distributed`` cluster of that many single-threaded
        worker processes when ``distributed`` is installed, else that many threads. None
        means the threaded scheduler with one thread per core.
    progress
        Show a progress bar for dask computations.
    """

    scheduler: str | None = None
    workers: int | None = None
    progress: bool = True


@contextmanager
def dask_context(options: ComputeOptions) -> Iterator[None]:
    """Configure dask for the duration of a stage according to ``options``."""
    with ExitStack() as stack:
        if options.scheduler:
            from distributed import Client  # optional dependency: g2tom[distributed]

            stack.enter_context(Client(options.scheduler))
        elif options.workers is not None and options.workers > 1 and _want_local_cluster():
            from distributed import Client, LocalCluster

            cluster = stack.enter_context(
                LocalCluster(n_workers=options.workers, threads_per_worker=1, processes=True)
            )
            stack.enter_context(Client(cluster))
        else:
            stack.enter_context(
                dask.config.set(scheduler="threads", num_workers=options.workers or os.cpu_count())
            )
        if options.progress and not options.scheduler:
            from dask.diagnostics import ProgressBar

            stack.enter_context(ProgressBar(minimum=3.0, dt=0.5))
        yield


def _want_local_cluster() -> bool:
    """A local ``distributed`` cluster is used for ``--workers`` when distributed is installed."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True
