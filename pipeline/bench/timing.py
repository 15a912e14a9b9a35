"""Wall-time measurement shared by the benchmarks: medians of repeated calls."""

from __future__ import annotations

import statistics
import time
from typing import Any, Callable

__all__ = ["median_time"]


def median_time(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """Median wall time of ``repeats`` calls of ``fn``, in s, and the last call's result.

    Parameters
    ----------
    fn
        The work to time, called without arguments.
    repeats
        Number of calls, >= 1.

    Returns
    -------
    tuple
        ``(median seconds, result of the last call)``.
    """
    if repeats < 1:
        raise ValueError(f"repeats = {repeats} is out of range: must be >= 1")
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result
