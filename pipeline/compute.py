"""Where dask work runs: the local threaded scheduler, a local cluster, or a remote one.

Whoever calls :func:`compute` (the CLI or a notebook) gets the same thread layout: one
BLAS/OpenMP thread per dask worker thread, set with ``threadpoolctl`` for the duration of
the computation (the many small dense products of the stages are several times slower when
every dask thread also starts one BLAS thread per core).
"""

from __future__ import annotations

import os
import sys
from contextlib import ExitStack
from dataclasses import dataclass
from typing import Any

import dask
from threadpoolctl import threadpool_limits

__all__ = ["ComputeOptions", "compute"]

#: Runs shorter than this (s) show no local progress bar.
PROGRESS_AFTER = 3.0
#: Seconds to wait for a remote scheduler before giving up.
CONNECT_TIMEOUT = 5.0


@dataclass(frozen=True)
class ComputeOptions:
    """How a stage computes.

    Attributes
    ----------
    scheduler
        Address of an existing ``dask.distributed`` scheduler, or None for local work.
    workers
        Local worker count: for more than one, a local ``dask.distributed`` cluster of that
        many single-threaded worker processes when ``distributed`` is installed; otherwise
        (and for one) that many threads. None means the threaded scheduler with one thread
        per core.
    progress
        Show a progress bar while computing.
    """

    scheduler: str | None = None
    workers: int | None = None
    progress: bool = True


def _distributed_available() -> bool:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def _client(stack: ExitStack, options: ComputeOptions) -> Any:
    """A ``distributed.Client`` for ``options``, or None for the local threaded scheduler."""
    if options.scheduler:
        from distributed import Client  # optional dependency: g2tom[distributed]

        return stack.enter_context(Client(options.scheduler, timeout=CONNECT_TIMEOUT))
    if options.workers is not None and options.workers > 1 and _distributed_available():
        from distributed import Client, LocalCluster

        cluster = stack.enter_context(
            LocalCluster(n_workers=options.workers, threads_per_worker=1, processes=True,
                         dashboard_address=None)
        )
        return stack.enter_context(Client(cluster))
    return None


def _show_progress(options: ComputeOptions) -> bool:
    """A progress bar only when asked and stderr is a terminal (no ``\\r`` spray into logs)."""
    return options.progress and sys.stderr.isatty()


def compute(*collections: Any, options: ComputeOptions) -> tuple[Any, ...]:
    """Compute dask collections where ``options`` says, with a progress bar if asked.

    Parameters
    ----------
    *collections
        Dask arrays or delayed objects.
    options
        Scheduler address, local worker count and progress display.

    Returns
    -------
    tuple
        The computed values, in the order given (as :func:`dask.compute`).
    """
    with ExitStack() as stack:
        client = _client(stack, options)
        if client is None:
            stack.enter_context(threadpool_limits(limits=1))
            stack.enter_context(
                dask.config.set(scheduler="threads", num_workers=options.workers or os.cpu_count())
            )
            if _show_progress(options):
                from dask.diagnostics import ProgressBar

                stack.enter_context(ProgressBar(minimum=PROGRESS_AFTER, dt=0.5, out=sys.stderr))
            return dask.compute(*collections)
        futures = client.compute(list(collections))
        if _show_progress(options):
            from distributed import progress

            progress(futures)
        return tuple(client.gather(futures))
