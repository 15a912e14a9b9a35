"""The phenomenological predictor of Eq. 27 and its error band, from a fitted surrogate.

    R_el = alpha(xi, lambda) 2 rho* / sqrt(R* sigma) F'^-gamma(xi, lambda),
    F' = 2 F / (E* sqrt(R* sigma^3)),   E* = E / (2 (1 - nu^2)),

with ``T(p) = sum_k P_k(w) Q_k(z)``, w = log(lambda), z = -log(1 - xi), T = log or identity
(the surrogate stage's model). Material (E, nu, rho*), roughness (sigma) and indenter (R*)
come from the scenario.

Two bands, each in ohm, each with one meaning, are built from three errors, each a
one-standard-deviation half-width in ln R (a relative error), interpolated linearly in
(w, z[, ln F']) from the grid tables of the surrogate stage and clamped to the grid:

* ``spread_lower`` = -ln(R'_16 / R'_c), ``spread_upper`` = ln(R'_84 / R'_c): the spread of
  single realizations (16-84 %, +inf above when more than 16 % are open circuits);
* ``fit_error`` = sqrt(s_a^2 + (ln F' s_g)^2), s_a and s_g one standard deviation of ln alpha
  and gamma from the fits' confidence intervals ((upper - lower) / (2 z_c));
* ``surrogate_error`` = sqrt(e_a^2 + (ln F' e_g)^2), e_a and e_g the local leave-one-line-out
  RMS errors of ln alpha and gamma.

The uncertainty of the predicted mean R takes the last two as independent (the fits stage
stores no covariance of alpha and gamma), combined in quadrature, as a 95 % interval:

    resistance_mean_lower, resistance_mean_upper = R exp(-/+ 1.96 sqrt(fit_error^2 + surrogate_error^2));

the spread over contacts is the first, ``resistance_spread_p16`` = R exp(-spread_lower),
``resistance_spread_p84`` = R exp(spread_upper).

A component that is unknown (NaN: e.g. a grid too small to cross-validate) is left out of the
mean's band, and a warning says so. Queries outside the fitted ranges of xi, lambda or F' are
NaN (``outside_domain`` says why) and the others answered; none inside is refused; all are
answered with ``extrapolate=True`` (then an :class:`ExtrapolationWarning`). Where the local
surrogate error exceeds ``warn_error`` a :class:`SurrogateErrorWarning` is issued.

The predictor works from ``surrogate.json`` alone (:mod:`g2tom.stages.surrogate_file`: the
coefficients, coordinate maps, scale conventions, fitted ranges and band tables) and gives the
same numbers from ``surrogate.nc``. The command ``g2tom predict`` is :mod:`g2tom.cli.predict`.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import xarray as xr

from g2tom.config import ConfigError, Scenario
from g2tom.predict.domain import answered_by, check_surface
from g2tom.predict.queries import (
    OUTPUT_COLUMNS,
    ExtrapolationWarning,
    SurrogateErrorWarning,
    Z95,
    check_values,
    outside_ranges,
    queries,
    settle_domain,
)
from g2tom.scene import scene_groups
from g2tom.stages.surrogate_file import GRID_TABLES, STEP_TABLES, SurrogateTables, load_surrogate
from g2tom.variables import namespace

__all__ = ["ExtrapolationWarning", "SurrogateErrorWarning", "SurrogateTables", "load_surrogate", "predict", "MODELS",
           "OUTPUT_COLUMNS"]

#: What :func:`predict` can answer with: the curve model (default) or Eq. 27's power law.
MODELS = ("curve", "power_law")


def _quadrature(*parts: np.ndarray) -> np.ndarray:
    """sqrt(sum of squares), unknown (NaN) parts left out."""
    return np.sqrt(sum(np.where(np.isnan(p), 0.0, p) ** 2 for p in parts))


def predict(
    surrogate: SurrogateTables | xr.Dataset,
    scenario: Scenario,
    force: Any,
    xi: Any,
    lam: Any,
    extrapolate: bool = False,
    warn_error: float | None = None,
    model: str = "curve",
) -> xr.Dataset:
    """R_el of the curve model (default) or Eq. 27 with its band and the band's components (see the module docstring).

    Parameters
    ----------
    surrogate
        :func:`load_surrogate` output, or the surrogate stage's dataset.
    scenario
        Supplies material (E, nu, rho*), roughness (sigma) and indenter (R*).
    force, xi, lam
        Normal force F (N, > 0), oxide fraction (in (0, 1)) and l_O sqrt(eta) (> 0): numbers,
        arrays that broadcast together, or xarray.DataArrays (broadcast by dimension name).
    extrapolate
        Allow queries outside the fitted ranges, or a surface other than the surrogate's (with a
        warning), instead of refusing them.
    warn_error
        Threshold on ``surrogate_error``; default ``scenario.surrogate.warn_error``.
    model
        ``curve``: each cell's curve model ln R'(ln F') interpolated between cells (its band:
        the mean curve's interval at that load and the grid's leave-one-out interpolation error);
        ``power_law``: Eq. 27 with the surrogate's alpha and gamma. Both are reported
        (``resistance_curve``, ``resistance_power_law``); ``resistance`` is the chosen one.

    Returns
    -------
    xarray.Dataset
        The variables of :data:`OUTPUT_COLUMNS`, shaped like the broadcast queries.

    Raises
    ------
    ConfigError
        If an input is non-finite or out of range, the inputs do not broadcast, or a query lies
        outside the fitted ranges and ``extrapolate`` is False, or the surface's (mu, Pi) differ
        from the surrogate's scene by more than
        :data:`g2tom.predict.domain.GROUP_TOLERANCE` (relative) and
        ``extrapolate`` is False.

    Warns
    -----
    ExtrapolationWarning, SurrogateErrorWarning
    """
    if model not in MODELS:
        raise ConfigError(f"model = {model!r} is not allowed: must be one of {', '.join(MODELS)}")
    tables = surrogate if isinstance(surrogate, SurrogateTables) else SurrogateTables.from_dataset(surrogate)
    (f, x, lm), label = queries(force, xi, lam)
    check_values(f, x, lm)
    check_surface(tables, scenario, extrapolate)
    force_n = f / scenario.force_scale
    problems, why = outside_ranges(tables.ranges, {"xi": x, "lambda": lm, "force_normalized": force_n},
                                   "the fitted range", scenario.force_scale)
    answered = settle_domain(problems, why, extrapolate, "")
    alpha = tables.parameter("alpha", lm, x)
    gamma = tables.parameter("gamma", lm, x)
    if np.any(~(alpha > 0)):
        i = int(np.flatnonzero(~(alpha > 0))[0])
        raise ConfigError(f"the surrogate gives alpha = {alpha[i]:.4g} <= 0 at xi = {x[i]:g}, lambda = {lm[i]:g}: "
                          "too far outside the fitted range")
    ln_f = np.log(force_n)
    power_law = alpha * scenario.resistance_scale * np.exp(-gamma * ln_f)
    curve = scenario.resistance_scale * np.exp(tables.curve(lm, x, force_n))
    s_a, s_g, e_a, e_g, e_curve = tables.interpolate(GRID_TABLES, lm, x).T
    ratio_lower, ratio_upper, open_p, s_curve = tables.interpolate(STEP_TABLES, lm, x, force_n).T
    with np.errstate(divide="ignore"):
        spread_lower, spread_upper = -np.log(ratio_lower), -np.log(ratio_upper)
    if model == "curve":
        resistance, fit_error, surrogate_error = curve, s_curve, e_curve
    else:
        resistance, fit_error, surrogate_error = power_law, np.hypot(s_a, ln_f * s_g), np.hypot(e_a, ln_f * e_g)
    if tables.lam.size == tables.xi.size == 1:
        surrogate_error = _single_cell(tables, surrogate_error)
    _warn_components(fit_error, surrogate_error, lm, x)
    threshold = scenario.surrogate.warn_error if warn_error is None else warn_error
    _warn_surrogate_error(surrogate_error, threshold, lm, x, force_n)
    mean_error = Z95 * _quadrature(fit_error, surrogate_error)
    columns = {
        "alpha": alpha, "gamma": gamma, "resistance": resistance,
        "resistance_mean_lower": resistance * np.exp(-mean_error), "resistance_mean_upper": resistance * np.exp(mean_error),
        "resistance_spread_p16": resistance * np.exp(-spread_lower),
        "resistance_spread_p84": resistance * np.exp(spread_upper),
        "spread_lower": spread_lower, "spread_upper": spread_upper, "fit_error": fit_error,
        "surrogate_error": surrogate_error, "open_probability": open_p, "resistance_curve": curve,
        "resistance_power_law": power_law,
    }
    groups = scene_groups(scenario)
    columns = {"force": f, "xi": x, "lambda": lm, "force_normalized": force_n,
               **{name: np.where(answered, values, np.nan) for name, values in columns.items()},
               "mu": np.full(f.size, groups.mu), "Pi": np.full(f.size, groups.Pi),
               "outside_domain": np.where(answered, "", why)}
    ds = xr.Dataset({name: label(values) for name, values in columns.items()})
    for name, var in namespace("predict").items():
        ds[name].attrs = var.attrs()
    ds.attrs["band"] = ("resistance_mean_lower, resistance_mean_upper = R exp(-/+ 1.96 sqrt(fit_error^2 + "
                        "surrogate_error^2)): the 95 % interval of the predicted mean R (the ensemble's interval and the "
                        "surrogate's cross-validated error)")
    ds.attrs["spread"] = ("resistance_spread_p16, resistance_spread_p84 = R exp(-spread_lower), R exp(spread_upper): "
                          "16-84 % of R over contacts (realizations)")
    ds.attrs["surrogate_method"] = str(tables.info.get("method", "unknown"))
    ds.attrs["model"] = model
    ds.attrs["answered_by"] = answered_by(tables)
    return ds


def _single_cell(tables: SurrogateTables, surrogate_error: np.ndarray) -> np.ndarray:
    """A one-cell surrogate answers with its cell's own fit, not an interpolation: no surrogate error.

    Returns zeros shaped like ``surrogate_error`` and says so (SurrogateErrorWarning), so the
    band is the realization spread and the fit interval only.
    """
    warnings.warn(f"the surrogate holds one cell (xi = {tables.xi[0]:g}, lambda = {tables.lam[0]:g}): the answer is that "
                  "cell's own fit, without interpolation; its band is the realization spread and the fit interval "
                  "(no surrogate error)", SurrogateErrorWarning, stacklevel=3)
    return np.zeros_like(surrogate_error)


def _warn_components(fit_error: np.ndarray, surrogate_error: np.ndarray, lam: np.ndarray, xi: np.ndarray) -> None:
    for name, values in (("fit confidence interval", fit_error), ("cross-validated surrogate error", surrogate_error)):
        unknown = np.flatnonzero(np.isnan(values))
        if unknown.size:
            i = unknown[0]
            warnings.warn(f"the {name} is unknown at {unknown.size} of {values.size} queries (first: xi = {xi[i]:g}, "
                          f"lambda = {lam[i]:g}); the band leaves it out there", SurrogateErrorWarning, stacklevel=3)


def _warn_surrogate_error(error: np.ndarray, threshold: float, lam: np.ndarray, xi: np.ndarray, force_n: np.ndarray) -> None:
    above = np.flatnonzero(error > threshold)
    if above.size:
        i = above[np.argmax(error[above])]
        warnings.warn(
            f"the surrogate's local cross-validated error exceeds surrogate.warn_error = {threshold:g} at {above.size} of "
            f"{error.size} queries (largest {error[i]:.3g} in ln R at xi = {xi[i]:g}, lambda = {lam[i]:g}, F' = {force_n[i]:.4g})",
            SurrogateErrorWarning, stacklevel=3,
        )
