"""Reductions of the resistance cube over realizations, as labelled xarray operations.

The fits stage reduces the cube with them (:func:`reduce_realizations`); the figures and the
report read the reductions from fits.nc.

Open circuits (R = +inf) are policy, not noise:

* ``geometric_mean`` and ``arithmetic_mean`` are taken over the *conducting* realizations
  only (NaN where none conducts) and are always reported beside ``open_probability``;
* ``median`` and ``quantile`` are taken over *all* realizations, an open circuit counting as
  +inf, so a quantile is +inf once more than the matching share of realizations is open.

Each reduction is a numpy kernel over the last axis (``*_of``) and its labelled wrapper over the
``realization`` dimension; the wrappers work on numpy- or dask-backed arrays (a chunked
realization axis is rechunked into one block).

Normalization (Eq. 25): ``R' = R sqrt(R* sigma) / (2 rho*)`` and
``F' = 2 F / (E* sqrt(R* sigma^3))``.
"""

from __future__ import annotations

import warnings
from typing import Callable

import numpy as np
import xarray as xr

from g2tom.fitting.powerlaw import quantile_with_inf
from g2tom.variables import namespace

__all__ = [
    "DIM",
    "QUANTILES",
    "geometric_mean_of",
    "arithmetic_mean_of",
    "quantiles_of",
    "open_share_of",
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


def _conducting(values: np.ndarray) -> np.ndarray:
    """``values`` with NaN in place of open circuits (and of any other non-finite value)."""
    return np.where(np.isfinite(values), values, np.nan)


def _nanmean(values: np.ndarray) -> np.ndarray:
    """Mean over the last axis of the non-NaN values; NaN (no warning) where there are none."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Mean of empty slice", RuntimeWarning)
        return np.nanmean(values, axis=-1)


def geometric_mean_of(values: np.ndarray) -> np.ndarray:
    """exp(mean(log R)) over the last axis of ``values`` (ohm), conducting samples only; NaN if none."""
    return np.exp(_nanmean(np.log(_conducting(values))))


def arithmetic_mean_of(values: np.ndarray) -> np.ndarray:
    """Mean over the last axis of ``values`` (ohm), conducting samples only; NaN if none."""
    return _nanmean(_conducting(values))


def quantiles_of(values: np.ndarray, q: tuple[float, ...] = QUANTILES) -> np.ndarray:
    """Linear-interpolation quantiles ``q`` over the last axis of ``values``, open circuits as +inf:
    shape (..., len(q))."""
    return np.stack([quantile_with_inf(values, qi) for qi in q], axis=-1)


def open_share_of(values: np.ndarray) -> np.ndarray:
    """Share of the samples on the last axis of ``values`` that are open circuits (+inf)."""
    return np.isposinf(values).mean(axis=-1)


def _over_realizations(kernel: Callable[..., np.ndarray], resistance: xr.DataArray, name: str,
                       q: tuple[float, ...] | None = None) -> xr.DataArray:
    """``kernel`` (a ``*_of`` function) over :data:`DIM` of ``resistance``, named ``name``; with ``q``, the
    quantiles' new dimension ``quantile``."""
    extra = {} if q is None else {"kwargs": {"q": tuple(q)}, "output_core_dims": [["quantile"]]}
    sizes = {} if q is None else {"output_sizes": {"quantile": len(q)}}
    out = xr.apply_ufunc(kernel, resistance, input_core_dims=[[DIM]], dask="parallelized", output_dtypes=[float],
                         dask_gufunc_kwargs={**sizes, "allow_rechunk": True}, **extra)
    return (out if q is None else out.assign_coords(quantile=list(q))).rename(name)


def open_probability(resistance: xr.DataArray) -> xr.DataArray:
    """Share of realizations that are open circuits (R = +inf), dimensionless."""
    return _over_realizations(open_share_of, resistance, "open_probability")


def geometric_mean(resistance: xr.DataArray) -> xr.DataArray:
    """exp(mean(log R)) over the conducting realizations; NaN if none conducts."""
    return _over_realizations(geometric_mean_of, resistance, "geometric_mean")


def arithmetic_mean(resistance: xr.DataArray) -> xr.DataArray:
    """Mean of R over the conducting realizations; NaN if none conducts."""
    return _over_realizations(arithmetic_mean_of, resistance, "arithmetic_mean")


def quantiles(resistance: xr.DataArray, q: tuple[float, ...] = QUANTILES) -> xr.DataArray:
    """Linear-interpolation quantiles over all realizations, open circuits as +inf.

    Returns
    -------
    xarray.DataArray
        The input's other dimensions plus ``quantile``.
    """
    return _over_realizations(quantiles_of, resistance, "resistance_quantile", q)


def median(resistance: xr.DataArray) -> xr.DataArray:
    """Median over all realizations, open circuits as +inf."""
    return quantiles(resistance, (0.5,)).squeeze("quantile", drop=True).rename("median")


#: The reductions of :func:`reduce_realizations`, each with its kernel (``quantile``'s adds a dimension).
_KERNELS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "geometric_mean": geometric_mean_of,
    "arithmetic_mean": arithmetic_mean_of,
    "median": lambda values: quantile_with_inf(values, 0.5),
    "resistance_quantile": quantiles_of,
    "open_probability": open_share_of,
}


def _by_counts(resistance: xr.DataArray, counts: np.ndarray) -> dict[str, xr.DataArray]:
    """Every reduction of :data:`_KERNELS`, each point of ``resistance`` (its dimensions but
    :data:`DIM`, which is last) over its own first ``counts`` realizations: one kernel call per
    distinct count."""
    values = resistance.values
    out = {name: np.empty(counts.shape + ((len(QUANTILES),) if name == "resistance_quantile" else ()))
           for name in _KERNELS}
    for n in np.unique(counts):
        at = counts == n
        block = values[at][:, : int(n)]
        for name, kernel in _KERNELS.items():
            out[name][at] = kernel(block)
    template = resistance.isel({DIM: 0}, drop=True)
    return {name: (template.copy(data=value) if value.ndim == template.ndim
                   else template.expand_dims(quantile=list(QUANTILES), axis=-1).copy(data=value)).rename(name)
            for name, value in out.items()}


def reduce_realizations(resistance: xr.DataArray, scale: float, counts: np.ndarray | None = None) -> xr.Dataset:
    """Every reduction of ``resistance`` and its normalized counterpart.

    Parameters
    ----------
    resistance
        Resistance in ohm with a ``realization`` dimension (+inf = open circuit).
    scale
        :attr:`g2tom.config.Scenario.resistance_scale`, ohm.
    counts
        How many of the first realizations each point reduces over (the shape of ``resistance``
        without ``realization``, which must then be its last dimension): the cells of an adaptive
        ensemble. None: every realization everywhere.

    Returns
    -------
    xarray.Dataset
        ``geometric_mean``, ``arithmetic_mean``, ``median``, ``resistance_quantile``
        (ohm; dimension ``quantile``), their
        ``*_normalized`` counterparts R' = R / scale, and ``open_probability``; their units
        and long names are fits.nc's (registry namespace ``stages.fits``, :mod:`g2tom.variables`).
    """
    if counts is None:
        reductions = {name: _over_realizations(kernel, resistance, name,
                                               QUANTILES if name == "resistance_quantile" else None)
                      for name, kernel in _KERNELS.items()}
    else:
        reductions = _by_counts(resistance, counts)
    declared = namespace("stages.fits")
    ds = xr.Dataset()
    for name, value in reductions.items():
        ds[name] = value.assign_attrs(declared[name].attrs())
        if name != "open_probability":
            ds[f"{name}_normalized"] = (value / scale).assign_attrs(declared[f"{name}_normalized"].attrs())
    ds["resistance_quantile"].attrs["policy"] = "over all realizations, open circuits as +inf"
    ds["geometric_mean"].attrs["policy"] = "over conducting realizations only"
    ds["arithmetic_mean"].attrs["policy"] = "over conducting realizations only"
    return ds
