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

from contextlib import AbstractContextManager
from typing import Any, Callable, TypeVar

from g2tom.compute import SharedResults

__all__ = ["once", "shared_cleans"]

T = TypeVar("T")

#: The clean surfaces kept inside :func:`shared_cleans`.
_CLEANS = SharedResults()


def once(compute: Callable[[], T], *inputs: Any) -> T:
    """``compute()``; inside :func:`shared_cleans`, a copy of the result of the first call whose
    ``inputs`` (everything ``compute`` reads, and a name for what it computes) were equal
    (``g2tom.compute.SharedResults.once``)."""
    return _CLEANS.once(compute, *inputs)


def shared_cleans() -> AbstractContextManager[None]:
    """Inside the block, :func:`once` computes each distinct clean surface once (nested blocks share
    the outer one's results)."""
    return _CLEANS.block()
