"""The clean surface's terms computed once per distinct input inside :func:`g2tom.models.shared_clean.shared_cleans`.

The cube of every scenario solves its oxide-free surface (the contact model's
:meth:`~g2tom.models.ContactModel.clean` and the conductances of Barber's check,
:func:`g2tom.stages.cube.clean_conductances`). A benchmark that builds the cube of several
scenarios on the same spots (``g2tom bench --only biases``: the steps that change only the oxide
fields, or only the cube's model, meet the surface of the step before) solves it once inside
:func:`g2tom.models.shared_clean.shared_cleans`: :func:`g2tom.models.shared_clean.once` keeps
each result by a digest of its inputs and gives the later calls a copy, equal to computing it
again. Outside the block it just computes.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
from contextlib import contextmanager
from typing import Any, Callable, Iterator, TypeVar

import numpy as np

__all__ = ["once", "shared_cleans"]

T = TypeVar("T")

#: The results :func:`once` keeps inside :func:`shared_cleans`, by the digest of their inputs; None outside.
_SHARED: dict[str, Any] | None = None


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


def once(compute: Callable[[], T], *inputs: Any) -> T:
    """``compute()``; inside :func:`shared_cleans`, a copy of the result of the first call whose
    ``inputs`` (everything ``compute`` reads, and a name for what it computes) were equal.

    Parameters
    ----------
    compute
        Computes the result from ``inputs`` alone.
    inputs
        Arrays, dataclasses (their compared fields), tuples and lists of them, or values
        whose repr identifies them.
    """
    if _SHARED is None:
        return compute()
    digest = hashlib.sha256()
    for part in inputs:
        _update(digest, part)
    key = digest.hexdigest()
    if key not in _SHARED:
        _SHARED[key] = compute()
    return copy.deepcopy(_SHARED[key])


@contextmanager
def shared_cleans() -> Iterator[None]:
    """Inside the block, :func:`once` computes each distinct clean surface once (nested blocks share
    the outer one's results)."""
    global _SHARED
    outer = _SHARED
    _SHARED = {} if outer is None else outer
    try:
        yield
    finally:
        _SHARED = outer
