"""The variable schema: each output variable's and coordinate's dims, units and long name.

:data:`SCHEMA` maps every stage file to its variables (the data variables and the coordinates
that carry attributes), read from the metadata registry (:mod:`g2tom.variables`, namespaces
``stages.*``, where each is declared once); a long name may hold ``{field}`` placeholders that
the writing stage fills from its settings (:meth:`Variable.attrs`). The stages, the atlas and the analysis take the
attributes from here; ``tests/fixtures/schema.json`` is the stored list the tests hold it to, and
the end-to-end test holds the written files to it.

Where two files label one coordinate differently today (``xi``: ``nominal oxide fraction`` in
oxide.nc, cube.nc and fits.nc, ``oxide fraction`` in surrogate.nc and the atlas), both labels are
declared, so the files' CF attributes stay as they were.
"""

from __future__ import annotations

from typing import Any

import xarray as xr

from g2tom.variables import Variable, namespace, texts

__all__ = ["Variable", "COORDINATES", "SURROGATE_COORDINATES", "RESISTANCE_LONG_NAMES", "SPOT_RADIUS_LONG_NAMES", "SCHEMA", "attrs",
           "variable", "labelled", "array", "matches", "label_coords"]


#: The coordinates that several files share, under the label most of them carry.
COORDINATES: dict[str, Variable] = namespace("stages.coordinates")

#: The labels of the coordinates of the surrogate and the atlas (their xi: see the module docstring).
SURROGATE_COORDINATES: dict[str, Variable] = namespace("stages.surrogate_coordinates")

#: The long name of contact.nc's ``spot_radius`` by ``contact.spots`` (its ``{spot_radius}`` slot).
SPOT_RADIUS_LONG_NAMES: dict[str, str] = texts("spot_radius")

#: The long name of the cube's ``resistance`` by ``cube.model`` (its ``{resistance}`` slot).
RESISTANCE_LONG_NAMES: dict[str, str] = texts("resistance")

#: Every stage file's variables and labelled coordinates.
SCHEMA: dict[str, dict[str, Variable]] = {
    stage: namespace(f"stages.{stage}") for stage in ("contact", "oxide", "cube", "fits", "surrogate")
}


def attrs(stage: str, name: str, **fields: Any) -> dict[str, str]:
    """The ``units`` and ``long_name`` of variable ``name`` of ``stage``'s file."""
    return SCHEMA[stage][name].attrs(**fields)


def variable(stage: str, name: str, data: Any, slots: dict[str, Any] | None = None,
             **extra: Any) -> tuple[tuple[str, ...], Any, dict[str, Any]]:
    """``(dims, data, attrs)`` of variable ``name`` of ``stage``'s file, for :class:`xarray.Dataset`:
    the long name's slots filled from ``slots``, ``extra`` attributes after ``units`` and ``long_name``."""
    var = SCHEMA[stage][name]
    return var.dims, data, {**var.attrs(**(slots or {})), **extra}


def labelled(var: Variable, data: Any, **fields: Any) -> tuple[tuple[str, ...], Any, dict[str, str]]:
    """``(dims, data, attrs)`` of ``var`` for :class:`xarray.Dataset`, ``long_name`` before ``units``: the
    attribute order of contact.nc's Greenwood–Tripp variables and of the benchmark files, kept as written."""
    found = var.attrs(**fields)
    return var.dims, data, {"long_name": found["long_name"], "units": found["units"]}


def array(stage: str, name: str, data: Any, slots: dict[str, Any] | None = None, **extra: Any) -> xr.DataArray:
    """Variable ``name`` of ``stage``'s file as a :class:`xarray.DataArray` (see :func:`variable`)."""
    dims, data, found = variable(stage, name, data, slots, **extra)
    return xr.DataArray(data, dims=dims, attrs=found)


def matches(stage: str, name: str, dims: tuple[str, ...], found: dict[str, Any]) -> bool:
    """Whether a written variable's dims, units and long name are those its schema declares."""
    var = SCHEMA[stage][name]
    return (tuple(dims) == var.dims and found.get("units") == var.units
            and bool(var.pattern().match(str(found.get("long_name", "")))))


def label_coords(ds: xr.Dataset) -> None:
    """Give every shared coordinate of ``ds`` (:data:`COORDINATES`) units and a long name if it lacks them."""
    for name, var in COORDINATES.items():
        if name in ds.coords:
            ds[name].attrs.setdefault("units", var.units)
            ds[name].attrs.setdefault("long_name", var.long_name)
