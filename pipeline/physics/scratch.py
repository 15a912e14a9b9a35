"""Per-thread work arrays reused by the hot loops of the interaction sums and the point solve.

With the allocator settings of ``dask.distributed`` workers (``MALLOC_TRIM_THRESHOLD_``) every
large allocation is a fresh, zeroed memory mapping, so the loops reuse their large temporaries
(:func:`scratch`), and the FFT path's zero-padded input keeps its padding between calls
(:func:`zero_padded`).
"""

from __future__ import annotations

import math
import threading

import numpy as np

__all__ = ["scratch", "zero_padded"]

_SCRATCH = threading.local()


def scratch(slot: str, shape: tuple[int, ...], dtype: type = np.float64) -> np.ndarray:
    """A work array of ``shape`` and ``dtype`` reused by this thread under ``slot`` (contents undefined).

    The hot loop reuses its large temporaries instead of allocating them afresh: with the
    allocator settings of ``dask.distributed`` workers (``MALLOC_TRIM_THRESHOLD_``) every large
    allocation is a fresh, zeroed memory mapping, which made the loop several times slower.
    """
    pool = getattr(_SCRATCH, "pool", None)
    if pool is None:
        pool = _SCRATCH.pool = {}
    size = math.prod(shape)
    key = (slot, np.dtype(dtype).char)
    flat = pool.get(key)
    if flat is None or flat.size < size:
        flat = pool[key] = np.empty(size, dtype)
    return flat[:size].reshape(shape)


def zero_padded(slot: str, shape: tuple[int, ...], dtype: type) -> np.ndarray:
    """:func:`scratch` of ``shape`` under ``slot``, zeroed whenever its shape or storage changes.

    Its users write only into a head of it, so the rest stays zero between calls of one shape.
    """
    view = scratch(slot, shape, dtype)
    zeroed = getattr(_SCRATCH, "zeroed", None)
    if zeroed is None:
        zeroed = _SCRATCH.zeroed = {}
    key = (slot, np.dtype(dtype).char)
    if zeroed.get(key) != (shape, id(view.base)):
        view.fill(0)
        zeroed[key] = (shape, id(view.base))
    return view
