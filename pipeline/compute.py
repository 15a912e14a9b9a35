"""Where dask work runs: the local threaded scheduler, a local cluster, or a remote one.

Whoever calls :func:`compute` (the CLI or a notebook) gets the same thread layout: one
BLAS/OpenMP thread per dask worker thread, set with ``threadpoolctl`` for the duration of
the computation (the many small dense products of the stages are several times slower when
every dask thread also starts one BLAS thread per core).

:class:`SharedResults` keeps results computed once per distinct input while a block is open: what
the benchmarks that build several scenarios on the same inputs share (the Greenwood–Tripp solve of
:func:`g2tom.contact_solution.shared_solves`, the clean surface of
:func:`g2tom.models.shared_clean.shared_cleans`).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import logging
import os
import signal
import threading
from contextlib import ExitStack, contextmanager, suppress
from dataclasses import dataclass
from multiprocessing import resource_tracker
from typing import Any, Callable, Iterator, TypeVar

import dask
import numpy as np
from threadpoolctl import threadpool_limits

from g2tom.progress import DaskProgress, ProgressLine, watch_futures

__all__ = ["ComputeOptions", "SharedResults", "children_ignore_interrupts", "compute", "in_turn", "single_threaded"]

#: Runs shorter than this (s) show no progress line.
PROGRESS_AFTER = 3.0
#: Seconds to wait for a remote scheduler before giving up.
CONNECT_TIMEOUT = 5.0


_F = TypeVar("_F", bound=Callable[..., Any])
_T = TypeVar("_T")


def single_threaded(function: _F) -> _F:
    """Run ``function`` with one BLAS/OpenMP thread (``threadpoolctl``), the previous limits restored after.

    The library's entry points (each stage's ``build`` and ``run``, the predict call) wear it, so that
    called from Python beside other work they do not start one BLAS thread per core in every dask
    thread; their parallelism is dask's. Calls nest (an inner call changes nothing).
    """

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with threadpool_limits(limits=1):
            return function(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


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
        Show a progress line with the time left while computing (on a terminal only, see
        :class:`g2tom.progress.ProgressLine`).
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


@contextmanager
def children_ignore_interrupts() -> Iterator[None]:
    """Threads started inside, and every process they start, never receive SIGINT.

    Ctrl-C in a terminal signals every process of the group: each worker process of a local
    cluster would print its own ``KeyboardInterrupt`` traceback (most often while still importing)
    beside the one line the main process writes. SIGINT is blocked in this (the main) thread
    meanwhile: a thread inherits the signal mask of the thread that starts it and a process that of
    the thread that forks it, and ``exec`` keeps it, so the cluster's event-loop thread, the threads
    it starts the workers from, and the workers keep SIGINT blocked for good; the main process stops
    the workers when it unwinds. The main thread's mask is back after, and a Ctrl-C meanwhile is
    not lost (pending, or taken by another thread for Python's handler), so this process still
    stops on it. Outside the main thread nothing is done.

    multiprocessing's resource tracker is started first: starting it unblocks SIGINT in the
    thread that does (the cluster's event loop otherwise), and with it in every thread that one
    starts.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    resource_tracker.ensure_running()
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _quiet_when_interrupted(kind: type[BaseException] | None, *_: object) -> None:
    """Exit callback of a local cluster: after Ctrl-C (or SIGTERM), asyncio's log is silenced before
    the cluster closes.

    The interrupted ``gather`` leaves tasks whose ``AllExit`` nobody retrieves, and asyncio logs
    each with a traceback when it is collected, after the one line the command prints. The level
    stays raised: the process is on its way out.
    """
    if kind is not None and issubclass(kind, KeyboardInterrupt):
        logging.getLogger("asyncio").setLevel(logging.CRITICAL)


#: Seconds a cluster interrupted while it starts is given to close.
ABANDON_TIMEOUT = 2.0


def _abandon(clusters: set[Any]) -> None:
    """Close clusters whose start was interrupted (SIGTERM, or Ctrl-C taken by the main thread), as
    far as they close, and take them off ``distributed``'s exit-time closing: closing a cluster
    whose workers are still starting fails on their state, and at exit that failure printed a
    traceback after the command's one line."""
    for cluster in clusters:
        with suppress(BaseException):
            cluster.close(timeout=ABANDON_TIMEOUT)
        cluster.shutdown_on_close = False


def _client(stack: ExitStack, options: ComputeOptions) -> Any:
    """A ``distributed.Client`` for ``options``, or None for the local threaded scheduler (the workers
    of a local cluster never receive SIGINT: :func:`children_ignore_interrupts`)."""
    if options.scheduler:
        from distributed import Client  # optional dependency: g2tom[distributed]

        return stack.enter_context(Client(options.scheduler, timeout=CONNECT_TIMEOUT))
    if options.workers is not None and options.workers > 1 and _distributed_available():
        from distributed import Client, LocalCluster
        from distributed.deploy.spec import SpecCluster

        before = set(SpecCluster._instances)
        try:
            with children_ignore_interrupts():
                cluster = LocalCluster(n_workers=options.workers, threads_per_worker=1, processes=True,
                                       dashboard_address=":0", silence_logs=logging.CRITICAL)
        except BaseException:
            _abandon(set(SpecCluster._instances) - before)
            raise
        stack.enter_context(cluster)
        client = stack.enter_context(Client(cluster))
        stack.push(_quiet_when_interrupted)
        return client
    return None


def in_turn(client: Any, function: Callable[..., Any], items: list[Any], key: Callable[[Any], str],
            *args: Any) -> Iterator[Any]:
    """``function(item, *args)`` of every item on a ``distributed`` cluster, started in the given order
    and never more at once than the cluster has threads; results as they complete.

    Submitted all at once, the scheduler spreads the tasks over the workers' queues in turn
    (their lengths unknown to it), so a long task queued early behind another long one waits
    there: measured on the full atlas, the third-longest scene (h05, ~25 min) started last, after
    its worker's first scene, and ran alone at the end. Holding back all but one task per thread
    keeps the order (the longest-first list the plan's wall time assumes).

    Parameters
    ----------
    client
        A ``distributed.Client``.
    function, args
        What to run: ``function(item, *args)``.
    items
        In the order to start them.
    key
        The task's key for an item.
    """
    from distributed import as_completed

    slots = max(sum(client.nthreads().values()), 1)
    waiting = iter(items)
    submit = lambda item: client.submit(function, item, *args, key=key(item), pure=False)  # noqa: E731
    running = as_completed([submit(item) for _, item in zip(range(slots), waiting)])
    for future in running:
        following = next(waiting, None)
        if following is not None:
            running.add(submit(following))
        yield future.result()


def compute(*collections: Any, options: ComputeOptions, label: str = "computing") -> tuple[Any, ...]:
    """Compute dask collections where ``options`` says, with a progress line if asked.

    Parameters
    ----------
    *collections
        Dask arrays or delayed objects.
    options
        Scheduler address, local worker count and progress display.
    label
        What the progress line calls this computation (e.g. ``cube round 2 (...)``).

    Returns
    -------
    tuple
        The computed values, in the order given (as :func:`dask.compute`).
    """
    # Only when asked and stderr is a terminal (no ``\r`` spray into logs), after PROGRESS_AFTER s.
    line = ProgressLine(label, after=PROGRESS_AFTER)
    show = options.progress and line.enabled
    with ExitStack() as stack:
        client = _client(stack, options)
        if client is None:
            stack.enter_context(threadpool_limits(limits=1))
            stack.enter_context(
                dask.config.set(scheduler="threads", num_workers=options.workers or os.cpu_count())
            )
            if show:
                stack.enter_context(DaskProgress(line))
            return dask.compute(*collections)
        if not show:
            return tuple(client.gather(client.compute(list(collections))))
        from distributed import futures_of

        # Persisted first, so the line counts every output chunk rather than whole collections.
        persisted = client.persist(list(collections))
        watch_futures(futures_of(persisted), line)
        return tuple(client.gather(client.compute(persisted)))


def _update(digest: Any, part: Any) -> None:
    """Feed ``part`` to ``digest``: arrays by dtype, shape and bytes, dataclasses by their compared
    fields, tuples and lists item by item, anything else by its repr."""
    if isinstance(part, np.ndarray):
        digest.update(repr((part.dtype.str, part.shape)).encode())
        digest.update(np.ascontiguousarray(part).tobytes())
    elif dataclasses.is_dataclass(part) and not isinstance(part, type):
        digest.update(type(part).__qualname__.encode())
        for item in dataclasses.fields(part):
            if item.compare:
                _update(digest, getattr(part, item.name))
    elif isinstance(part, (tuple, list)):
        digest.update(f"{type(part).__name__}{len(part)}".encode())
        for item in part:
            _update(digest, item)
    else:
        digest.update(repr(part).encode())
    digest.update(b"|")


class SharedResults:
    """Results kept by their inputs' digest while a :meth:`block` is open (nested blocks share the
    outer one's results)."""

    def __init__(self) -> None:
        self._results: dict[str, Any] | None = None

    @property
    def active(self) -> bool:
        """Whether a block is open (callers whose inputs are costly to gather skip it outside)."""
        return self._results is not None

    @contextmanager
    def block(self) -> Iterator[None]:
        """Keep results until the outermost block closes."""
        outer = self._results
        self._results = {} if outer is None else outer
        try:
            yield
        finally:
            self._results = outer

    def once(self, compute: Callable[[], _T], *inputs: Any) -> _T:
        """``compute()``; inside a block, a copy of the result of the first call whose ``inputs``
        (everything ``compute`` reads, and a name for what it computes) were equal.

        Parameters
        ----------
        compute
            Computes the result from ``inputs`` alone.
        inputs
            Arrays, dataclasses (their compared fields), tuples and lists of them, or values whose
            repr identifies them.
        """
        if self._results is None:
            return compute()
        digest = hashlib.sha256()
        for part in inputs:
            _update(digest, part)
        key = digest.hexdigest()
        if key not in self._results:
            self._results[key] = compute()
        return copy.deepcopy(self._results[key])
