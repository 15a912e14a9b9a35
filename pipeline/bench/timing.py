"""Wall-time measurement shared by the benchmarks: medians of repeated calls, each as a first call
would run (no influence matrix kept from the one before)."""

from __future__ import annotations

import statistics
import time
from typing import Any, Callable

from g2tom.physics.radial_grid import forget_kept_matrices

__all__ = ["median_time"]


def median_time(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """Median wall time of ``repeats`` calls of ``fn``, in s, and the last call's result; before each
    call the influence matrices kept by earlier solves are dropped
    (:func:`g2tom.physics.radial_grid.forget_kept_matrices`), so that repeats time what one call costs.

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
        forget_kept_matrices()
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result
