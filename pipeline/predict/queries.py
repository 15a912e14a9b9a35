"""The predictors' queries: broadcasting (numbers, arrays or DataArrays), their allowed values,
the fitted ranges (refused, or warned with ``extrapolate``), and the output columns both
predictors (:mod:`g2tom.predict.predictor`, :mod:`g2tom.predict.atlas`) answer with."""

from __future__ import annotations

import warnings
from typing import Any, Callable

import numpy as np
import xarray as xr

from g2tom.config import ConfigError

__all__ = ["ExtrapolationWarning", "SurrogateErrorWarning", "queries", "check_values", "check_ranges",
           "OUTPUT_COLUMNS"]


class ExtrapolationWarning(UserWarning):
    """xi, lambda or F' lies outside the range the surrogate was fitted on."""


class SurrogateErrorWarning(UserWarning):
    """The surrogate's local cross-validated error exceeds the warning threshold."""


def queries(force: Any, xi: Any, lam: Any) -> tuple[list[np.ndarray], Callable[[np.ndarray], Any]]:
    """Flat float arrays of the broadcast queries, and a function that labels a flat result."""
    given = {"force": force, "xi": xi, "lambda": lam}
    if any(isinstance(v, xr.DataArray) for v in given.values()):
        for name, v in given.items():
            if not isinstance(v, xr.DataArray) and np.ndim(v) != 0:
                raise ConfigError(f"{name} is an array but another query is an xarray.DataArray: give DataArrays or scalars")
        arrays = xr.broadcast(*[v if isinstance(v, xr.DataArray) else xr.DataArray(float(v)) for v in given.values()])
        template = arrays[0]
        flat = [np.asarray(a.transpose(*template.dims).values, dtype=float).ravel() for a in arrays]
        coords = {k: c for k, c in template.coords.items() if set(c.dims) <= set(template.dims)}

        def label(values: np.ndarray) -> xr.DataArray:
            return xr.DataArray(values.reshape(template.shape), dims=template.dims, coords=coords)

        return flat, label
    try:
        arrays = [np.asarray(v, dtype=float) for v in given.values()]
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError:
        shapes = ", ".join(f"{n} {np.shape(v)}" for n, v in given.items())
        raise ConfigError(f"force, xi and lambda must be numbers or arrays that broadcast together; got shapes {shapes}") from None
    except TypeError as exc:
        raise ConfigError(f"force, xi and lambda must be numbers ({exc})") from None
    dims = ("query",) if len(shape) == 1 else tuple(f"query_{k}" for k in range(len(shape)))

    def label_np(values: np.ndarray) -> xr.DataArray:
        return xr.DataArray(values.reshape(shape), dims=dims)

    return [np.broadcast_to(a, shape).ravel() for a in arrays], label_np


def check_values(force: np.ndarray, xi: np.ndarray, lam: np.ndarray) -> None:
    """Refuse (ConfigError, naming the first bad query) a force, xi or lambda outside its allowed range."""
    checks = (
        ("force", force, lambda v: np.isfinite(v) & (v > 0), "must be finite and > 0 (N)"),
        ("xi", xi, lambda v: np.isfinite(v) & (v > 0) & (v < 1), "must be in (0, 1)"),
        ("lambda", lam, lambda v: np.isfinite(v) & (v > 0), "must be finite and > 0"),
    )
    for name, values, ok, allowed in checks:
        bad = np.flatnonzero(~ok(values))
        if bad.size:
            where = f" (query {bad[0] + 1} of {values.size})" if values.size > 1 else ""
            raise ConfigError(f"{name} = {float(values[bad[0]])!r}{where} is out of range: {allowed}")


def check_ranges(ranges: dict[str, tuple[float, float]], values: dict[str, np.ndarray], extrapolate: bool,
                 span: str = "the fitted range", owner: str = "") -> None:
    """Refuse (ConfigError) queries outside ``ranges``, or with ``extrapolate`` warn
    (:class:`ExtrapolationWarning`): ``"<name> = <value> lies outside <span> [lo, hi]<owner>"``."""
    for name, v in values.items():
        lo, hi = ranges[name]
        outside = np.flatnonzero((v < lo * (1 - 1e-12)) | (v > hi * (1 + 1e-12)))
        if not outside.size:
            continue
        i = outside[0]
        label = "F'" if name == "force_normalized" else name
        where = f" (query {i + 1} of {v.size}; {outside.size} outside)" if v.size > 1 else ""
        text = f"{label} = {v[i]:.6g}{where} lies outside {span} [{lo:.6g}, {hi:.6g}]{owner}"
        if not extrapolate:
            raise ConfigError(f"{text}: the surrogate is not valid there; pass --extrapolate (extrapolate=True) to predict anyway")
        warnings.warn(f"{text}: the prediction is an extrapolation", ExtrapolationWarning, stacklevel=3)


#: Output variables of :func:`predict`: name -> (units, long_name).
OUTPUT_COLUMNS: dict[str, tuple[str, str]] = {
    "force": ("N", "normal force F"),
    "xi": ("1", "oxide fraction"),
    "lambda": ("1", "normalized oxide correlation length l_O sqrt(eta)"),
    "force_normalized": ("1", "F' = 2F/(E* sqrt(R* sigma^3))"),
    "alpha": ("1", "surrogate factor alpha"),
    "gamma": ("1", "surrogate exponent gamma"),
    "resistance": ("ohm", "R_el of the chosen model (curve by default; Eq. 27 with model = power_law)"),
    "lower": ("ohm", "lower end of the combined band R exp(-total_lower)"),
    "upper": ("ohm", "upper end of the combined band R exp(total_upper)"),
    "realization_lower": ("ohm", "16 % of single realizations, R exp(-spread_lower)"),
    "realization_upper": ("ohm", "84 % of single realizations, R exp(spread_upper) (inf: > 16 % open circuits)"),
    "spread_lower": ("1", "realization spread below R, one-sigma half-width in ln R"),
    "spread_upper": ("1", "realization spread above R, one-sigma half-width in ln R"),
    "fit_error": ("1", "fit confidence interval, one-sigma half-width in ln R"),
    "surrogate_error": ("1", "local cross-validated surrogate error, one-sigma half-width in ln R"),
    "total_lower": ("1", "combined half-width below R in ln R (quadrature sum)"),
    "total_upper": ("1", "combined half-width above R in ln R (quadrature sum)"),
    "open_probability": ("1", "interpolated share of open-circuit realizations"),
    "resistance_curve": ("ohm", "R_el of the curve model (ln R' polynomial in ln F' per cell, interpolated)"),
    "resistance_power_law": ("ohm", "R_el of Eq. 27 with the surrogate's alpha and gamma"),
    "mu": ("1", "the surface's (8/3) eta sigma sqrt(2 R* beta)"),
    "Pi": ("1", "the surface's eta R* sigma"),
}
