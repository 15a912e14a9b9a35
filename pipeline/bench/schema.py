"""The variable schema of the benchmarks' netCDF files: each variable's dims, units and long name, read
from the metadata registry (:mod:`g2tom.variables`, namespaces ``bench.*``, where each is declared once).

``bench/frontier.nc`` (:mod:`g2tom.bench.frontier`: :data:`FRONTIER`, the sweep tables'
columns by :func:`sweep_column`) and ``bench/stability.nc`` (:mod:`g2tom.bench.stability`:
:data:`STABILITY`), in the form of the stage files' schema (:mod:`g2tom.stages.schema`).
Their attributes are written long name first (:func:`g2tom.stages.schema.labelled`), as
they always were.
"""

from __future__ import annotations

from g2tom.variables import Variable, namespace, texts

__all__ = ["FRONTIER", "STABILITY", "SWEEP_UNITS", "sweep_column", "sweep_index"]


#: frontier.nc: the ensemble sweep and the adaptive cube's prefix curve (the sweep tables: :func:`sweep_column`).
FRONTIER: dict[str, Variable] = namespace("bench.frontier")

#: The sweep tables' column and index, ``{table}`` (and ``{key}``) slots in their dims and long names.
_SWEEP: dict[str, Variable] = namespace("bench.sweep")

#: Units of the sweep tables' columns that have one; every other column takes ``_SWEEP["column"]``'s.
SWEEP_UNITS: dict[str, str] = texts("sweep_units")


def _filled(var: Variable, units: str, **fields: str) -> Variable:
    """``var`` with the slots of its dims and long name filled from ``fields`` and the given units."""
    return Variable(tuple(d.format(**fields) for d in var.dims), units, var.long_name.format(**fields))


def sweep_column(table: str, key: str) -> Variable:
    """Column ``key`` of the sweep ``table`` (``contact`` or ``cube``) of frontier.nc: ``<table>_<key>``."""
    column = _SWEEP["column"]
    return _filled(column, SWEEP_UNITS.get(key, column.units), table=table, key=key.replace("_", " "))


def sweep_index(table: str) -> Variable:
    """The coordinate of the sweep ``table``: one index per setting."""
    index = _SWEEP["index"]
    return _filled(index, index.units, table=table)


#: stability.nc: one entry per case of the stability map.
STABILITY: dict[str, Variable] = namespace("bench.stability")
