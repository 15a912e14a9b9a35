"""validate.nc's variables: each one's dims, units and long name, read from the metadata registry
(:mod:`g2tom.variables`, namespace ``validate``, where each is declared once; as :mod:`g2tom.stages.schema`).

Part 1 (*exactness per surface*, paired): the full field and g2tom per realization and load.
Part 2 (*the default's ensemble*, unpaired): the validated scenario's ensemble geometric mean of R
against the full field's, per load, with standard errors (variables ``ensemble_*``).
"""

from __future__ import annotations

from typing import Any

from g2tom.variables import Variable, namespace

__all__ = ["VARIABLES", "variable"]


#: Every variable and labelled coordinate of validate.nc.
VARIABLES: dict[str, Variable] = namespace("validate")


def variable(name: str, data: Any, **extra: Any) -> tuple[tuple[str, ...], Any, dict[str, Any]]:
    """``(dims, data, attrs)`` of validate.nc's variable ``name`` for :class:`xarray.Dataset`
    (``extra`` attributes, e.g. a ``comment``, after ``units`` and ``long_name``)."""
    var = VARIABLES[name]
    return var.dims, data, {**var.attrs(), **extra}
