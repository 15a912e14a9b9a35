"""Reductions of the resistance cube over realizations, as labelled xarray operations.

The fits stage reduces the cube with them (:func:`reduce_realizations`); the figures and the
report read the reductions from fits.nc.

Open circuits (R = +inf) are policy, not noise:

* ``geometric_mean`` and ``arithmetic_mean`` are taken over the *conducting* realizations
  only (NaN where none conducts) and are always reported beside ``open_probability``;
* ``median`` and ``quantile`` are taken over *all* realizations, an open circuit counting as
  +inf, so a quantile is +inf once more than the matching share of realizations is open.

Every function works on numpy- or dask-backed arrays (the realization axis may be chunked
for the means; the quantiles rechunk it into one block).

Normalization (Eq. 25): ``R' = R sqrt(R* sigma) / (2 rho*)`` and
``F' = 2 F / (E* sqrt(R* sigma^3))``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from g2tom.fitting.powerlaw import quantile_with_inf
from g2tom.variables import namespace

__all__ = [
    "DIM",
    "QUANTILES",
    "open_probability",
    "geometric_mean",
    "arithmetic_mean",
    "quantiles",
    "median",
    "reduce_realizations",
]

#: The dimension reduced over.
DIM = "realization"
#: Quantiles of the band (16 % and 84 %) and the median.
QUANTILES = (0.16, 0.5, 0.84)


def open_probability(resistance: xr.DataArray) -> xr.DataArray:
    """Share of realizations that are open circuits (R = +inf), dimensionless."""
    return np.isposinf(resistance).mean(DIM).rename("open_probability")


def geometric_mean(resistance: xr.DataArray) -> xr.DataArray:
    """exp(mean(log R)) over the conducting realizations; NaN if none conducts."""
    finite = resistance.where(np.isfinite(resistance))
    return np.exp(np.log(finite).mean(DIM, skipna=True)).rename("geometric_mean")


def arithmetic_mean(resistance: xr.DataArray) -> xr.DataArray:
    """Mean of R over the conducting realizations; NaN if none conducts."""
    finite = resistance.where(np.isfinite(resistance))
    return finite.mean(DIM, skipna=True).rename("arithmetic_mean")


def _quantile_block(values: np.ndarray, q: tuple[float, ...]) -> np.ndarray:
    return np.stack([quantile_with_inf(values, qi) for qi in q], axis=-1)


def quantiles(resistance: xr.DataArray, q: tuple[float, ...] = QUANTILES) -> xr.DataArray:
    """Linear-interpolation quantiles over all realizations, open circuits as +inf.

    Returns
    -------
    xarray.DataArray
        The input's other dimensions plus ``quantile``.
    """
    out = xr.apply_ufunc(
        _quantile_block,
        resistance,
        kwargs={"q": tuple(q)},
        input_core_dims=[[DIM]],
        output_core_dims=[["quantile"]],
        dask="parallelized",
        output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": {"quantile": len(q)}, "allow_rechunk": True},
    )
    return out.assign_coords(quantile=list(q)).rename("resistance_quantile")


def median(resistance: xr.DataArray) -> xr.DataArray:
    """Median over all realizations, open circuits as +inf."""
    return quantiles(resistance, (0.5,)).squeeze("quantile", drop=True).rename("median")


def reduce_realizations(resistance: xr.DataArray, scale: float) -> xr.Dataset:
    """Every reduction of ``resistance`` and its normalized counterpart.

    Parameters
    ----------
    resistance
        Resistance in ohm with a ``realization`` dimension (+inf = open circuit).
    scale
        :attr:`g2tom.config.Scenario.resistance_scale`, ohm.

    Returns
    -------
    xarray.Dataset
        ``geometric_mean``, ``arithmetic_mean``, ``median``, ``resistance_quantile``
        (ohm; dimension ``quantile``), their
        ``*_normalized`` counterparts R' = R / scale, and ``open_probability``; their units
        and long names are fits.nc's (registry namespace ``stages.fits``, :mod:`g2tom.variables`).
    """
    reductions = {
        "geometric_mean": geometric_mean(resistance),
        "arithmetic_mean": arithmetic_mean(resistance),
        "median": median(resistance),
        "resistance_quantile": quantiles(resistance),
    }
    declared = namespace("stages.fits")
    ds = xr.Dataset()
    for name, value in reductions.items():
        ds[name] = value.assign_attrs(declared[name].attrs())
        ds[f"{name}_normalized"] = (value / scale).assign_attrs(declared[f"{name}_normalized"].attrs())
    ds["open_probability"] = open_probability(resistance).assign_attrs(declared["open_probability"].attrs())
    ds["resistance_quantile"].attrs["policy"] = "over all realizations, open circuits as +inf"
    ds["geometric_mean"].attrs["policy"] = "over conducting realizations only"
    ds["arithmetic_mean"].attrs["policy"] = "over conducting realizations only"
    return ds
