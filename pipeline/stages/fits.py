"""Stage 4: reductions over realizations, power-law fits R' = alpha F'^-gamma (Eq. 25) and curves.

Reads ``cube.nc``, writes ``fits.nc``. For every (xi, lambda) the chosen reduction
(``fits.reduction``, geometric mean by default) of R' is fitted by least squares in log-log
over the fitted load steps, F >= ``fits.min_force`` (N) or, with ``fits.fit_range =
"force_normalized"``, F' >= ``fits.min_force_normalized``; the clean surface is fitted the same way.

Curve model (:mod:`g2tom.fitting.curve_model`): on the same steps, ln R' of the reduction is
also fitted by the lowest-order polynomial in ln F' (up to ``fits.curve_max_order``) that lies
within ``fits.curve_tolerance`` at every fitted step or, failing that, within max(tolerance,
the step's bootstrap interval of the reduction); the clean curve has no interval.

Uncertainty: percentile bootstrap over realizations (``fits.n_bootstrap`` resamples, seed
``fits.seed``, level ``fits.confidence``): each resample redraws the realizations with
replacement, recomputes the reduction at every fitted step and refits. The clean surface
has a single deterministic curve, so its interval is the classical least-squares one
(Student t on the fitted steps) and only reflects the misfit of the power law.

Ensembles of different sizes: a cube may hold ``n_realizations(xi, lambda)`` realizations per
cell (the adaptive ensemble, NaN beyond). Every reduction and the bootstrap of a cell use that
cell's realizations only; one resample table is drawn per distinct count, in ascending order of
the counts, from the one generator (a fixed ensemble thus draws exactly one table, as before).
Cells that stopped at the cap short of the target are flagged.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import special

from g2tom.compute import ComputeOptions, single_threaded
from g2tom.config import Scenario
from g2tom.fitting.control_variate import bootstrap_controlled_mean, controllable, controlled_mean
from g2tom.fitting.curve_model import CurveFit, fit_curve
from g2tom.fitting.powerlaw import (
    bootstrap_log_mean,
    bootstrap_median,
    fit_power_law,
    percentile_interval,
    resample_counts,
)
from g2tom.reductions import DIM, reduce_realizations
from g2tom.stages.fit_steps import fitted_steps, range_label
from g2tom.stages.schema import attrs, label_coords, variable
from g2tom.store import read_stage, write_dataset

__all__ = ["build", "run"]

GRID = ("xi", "lambda")
#: The cube's per-realization variables the fits read; the others (the resistance's self and interaction
#: terms, the conducting counts, the solver's report) are not loaded.
REDUCED = ("resistance", "clean_share")


def _bootstrap(
    scenario: Scenario, normalized: np.ndarray, force_n: np.ndarray, counts: np.ndarray,
    control: tuple[np.ndarray, np.ndarray] | None = None, step_counts: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bootstrap alpha and gamma, each shaped (xi, lambda, resample), and the interval of the
    reduction at every fitted step, (xi, lambda, step, bound).

    ``normalized`` holds R' on the fitted steps, shape (xi, lambda, step, realization); cell
    (xi, lambda) uses its first ``counts[xi, lambda]`` realizations, or at each step its first
    ``step_counts[xi, lambda, step]`` (``oxide.step_half_width``: one table of the lightest step's
    count serves the cell, each step taking its columns of its own realizations, so a resample
    redraws a realization at every step that holds it). ``control``: the control variate's values
    (shaped as ``normalized``) and expectations (xi, lambda), or None.
    """
    rng = np.random.default_rng(scenario.fits.seed)
    alpha = np.empty(counts.shape + (scenario.fits.n_bootstrap,))
    gamma = np.empty_like(alpha)
    band = np.empty(counts.shape + (normalized.shape[2], 2))
    per_cell = counts[..., None] if step_counts is None else step_counts
    keys = {tuple(int(n) for n in per_cell[z, a]) for z, a in np.ndindex(counts.shape)}
    for key in sorted(keys, key=lambda k: (max(k), k)):  # ascending (one count per cell: as the counts)
        n = max(key)
        table = resample_counts(n, scenario.fits.n_bootstrap, rng)
        steps = None if len(set(key)) == 1 else np.array(key)
        if len(keys) == 1 and steps is None:  # one count (a fixed ensemble): the whole grid at once
            return _bootstrap_fit(scenario, normalized[..., :n], force_n, table,
                                  None if control is None else (control[0][..., :n], control[1]))
        cells = np.nonzero(np.all(per_cell == np.array(key), axis=-1))
        part = None if control is None else (control[0][..., :n][cells], control[1][cells])
        alpha[cells], gamma[cells], band[cells] = _bootstrap_fit(scenario, normalized[..., :n][cells], force_n, table,
                                                                 part, steps)
    return alpha, gamma, band


def _bootstrap_fit(
    scenario: Scenario, values: np.ndarray, force_n: np.ndarray, table: np.ndarray,
    control: tuple[np.ndarray, np.ndarray] | None = None, steps: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """alpha and gamma (..., resample) of the resamples ``table`` of ``values`` (..., step,
    realization), and the interval of the reduction at every step (..., step, bound); ``steps``:
    the realizations of each step (step,), each taking the table's first that many columns."""
    if steps is None:
        reduced = _resampled(scenario, values, table, control)
    else:
        reduced = np.empty(values.shape[:-1] + (table.shape[0],))
        for n in np.unique(steps):
            at = np.flatnonzero(steps == n)
            part = None if control is None else (control[0][..., at, :n], control[1])
            reduced[..., at, :] = _resampled(scenario, values[..., at, :n], table[:, :n], part)
    fit = fit_power_law(force_n, np.moveaxis(reduced, -1, -2))
    return fit.alpha, fit.gamma, _interval(reduced, scenario.fits.confidence)


def _resampled(scenario: Scenario, values: np.ndarray, table: np.ndarray,
               control: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray:
    """The reduction of every resample ``table`` of ``values`` (..., step, realization), (..., step, resample)."""
    if scenario.fits.reduction == "median":
        return bootstrap_median(values, table)
    if control is not None:
        return bootstrap_controlled_mean(values, control[0], control[1][..., None], table)
    return bootstrap_log_mean(values, table, scenario.fits.reduction == "geometric_mean")


def _counts(cube: xr.Dataset) -> np.ndarray:
    """Realizations per (xi, lambda): the cube's ``n_realizations``, else the whole axis."""
    if "n_realizations" in cube:
        return cube["n_realizations"].transpose(*GRID).values.astype(int)
    return np.full((cube.sizes["xi"], cube.sizes["lambda"]), cube.sizes[DIM])


def _step_counts(cube: xr.Dataset) -> np.ndarray | None:
    """Realizations per (xi, lambda, delta) where the cube has them (``oxide.step_half_width``), else None."""
    if "step_realizations" not in cube:
        return None
    return cube["step_realizations"].transpose(*GRID, "delta").values.astype(int)


def _reduce(resistance: xr.DataArray, counts: np.ndarray, scale: float,
            step_counts: np.ndarray | None = None) -> xr.Dataset:
    """:func:`reduce_realizations` of every (xi, lambda) over its own realizations (at each step its
    own, with ``step_counts``)."""
    if step_counts is None and np.all(counts == resistance.sizes[DIM]):
        return reduce_realizations(resistance, scale)
    own = step_counts if step_counts is not None else np.broadcast_to(counts[:, :, None], resistance.shape[:-1])
    return reduce_realizations(resistance, scale, counts=own)


def _control(cube: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """The cube's control variate (xi, lambda, delta, realization) and its expectation (xi, lambda).

    Raises
    ------
    ValueError
        If the cube holds no control variate (computed without ``fits.control_variate``).
    """
    if "clean_share" not in cube:
        raise ValueError("cube.nc holds no clean_share: it was computed without fits.control_variate; rerun the cube")
    return (cube["clean_share"].transpose(*GRID, "delta", DIM).values,
            cube["clean_share_expected"].transpose(*GRID).values)


def _controlled_reduction(ds: xr.Dataset, resistance: np.ndarray, control: tuple[np.ndarray, np.ndarray],
                          counts: np.ndarray, scale: float, step_counts: np.ndarray | None = None) -> None:
    """Replace the geometric mean (and R') of ``ds`` by its control-variate estimate
    (:mod:`g2tom.fitting.control_variate`; the plain mean where it does not apply), each (xi,
    lambda) over its own realizations (at each step its own, with ``step_counts``), and record where
    it applied (``control_variate_applied``)."""
    values, expected = control
    mean = ds["geometric_mean"].transpose(*GRID, "delta").values.copy()
    applied = np.zeros(mean.shape, np.int8)
    for z, a in np.ndindex(counts.shape):
        own = np.full(mean.shape[-1], counts[z, a]) if step_counts is None else step_counts[z, a]
        for n in np.unique(own):
            at = slice(None) if np.all(own == n) else np.flatnonzero(own == n)
            r, x = resistance[z, a, at, :n], values[z, a, at, :n]
            applied[z, a, at] = controllable(r, x)
            mean[z, a, at] = controlled_mean(r, x, expected[z, a])
    method = ("control variate where control_variate_applied: (mean(y c) - b_n (mean(x) - p)) / (mean(c) - b_d "
              "(mean(x) - p)), y = ln R, c = 1 where conducting, x the spots' radius-weighted clean share, p its "
              "exact expectation")
    for name, value in (("geometric_mean", mean), ("geometric_mean_normalized", mean / scale)):
        ds[name] = ds[name].transpose(*GRID, "delta").copy(data=value)
        ds[name].attrs["method"] = method
    ds["control_variate_applied"] = variable("fits", "control_variate_applied", applied)


def _interval(samples: np.ndarray, confidence: float) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN cells stay NaN
        return percentile_interval(samples, confidence)


def _clean_fit(scenario: Scenario, clean: np.ndarray, force_n: np.ndarray, mask: np.ndarray) -> dict[str, xr.DataArray]:
    """Least-squares fit of the clean surface with Student-t intervals."""
    fit = fit_power_law(force_n, clean, mask)
    lx = np.log(force_n[np.isfinite(fit.residual)])  # the steps that entered the fit
    n = lx.size
    dof = n - 2  # no interval from two points: the line passes through both
    t = special.stdtrit(dof, 0.5 * (1.0 + scenario.fits.confidence)) if dof >= 1 else np.nan
    s2 = np.nansum(fit.residual**2) / dof if dof >= 1 else np.nan
    sxx = np.sum((lx - lx.mean()) ** 2)
    se_slope = np.sqrt(s2 / sxx)
    se_intercept = np.sqrt(s2 * (1.0 / n + lx.mean() ** 2 / sxx))
    log_alpha = np.log(fit.alpha)
    bound = {"bound": ["lower", "upper"]}
    return {
        "alpha_clean": xr.DataArray(fit.alpha, attrs=attrs("fits", "alpha_clean")),
        "gamma_clean": xr.DataArray(fit.gamma, attrs=attrs("fits", "gamma_clean")),
        "alpha_clean_ci": xr.DataArray(
            np.exp([log_alpha - t * se_intercept, log_alpha + t * se_intercept]), dims="bound", coords=bound,
            attrs={**attrs("fits", "alpha_clean_ci"), "method": "least-squares Student t"},
        ),
        "gamma_clean_ci": xr.DataArray(
            [fit.gamma - t * se_slope, fit.gamma + t * se_slope], dims="bound", coords=bound,
            attrs={**attrs("fits", "gamma_clean_ci"), "method": "least-squares Student t"},
        ),
        "fit_residual_clean": xr.DataArray(fit.residual, dims="delta", attrs=attrs("fits", "fit_residual_clean")),
        "fit_residual_rms_clean": xr.DataArray(fit.residual_rms, attrs=attrs("fits", "fit_residual_rms_clean")),
    }


def _ensemble_summary(
    scenario: Scenario, cube: xr.Dataset, ds: xr.Dataset, counts: np.ndarray
) -> dict[str, xr.DataArray]:
    """Realizations used, reached half-widths and flags per (xi, lambda)."""
    lower, upper = ds["alpha_ci"].sel(bound="lower"), ds["alpha_ci"].sel(bound="upper")
    g_lower, g_upper = ds["gamma_ci"].sel(bound="lower"), ds["gamma_ci"].sel(bound="upper")
    used = xr.DataArray(counts, dims=GRID)
    out = {
        "n_realizations": used.astype(np.int32).assign_attrs(attrs("fits", "n_realizations")),
        "alpha_half_width": ((upper - lower) / (2.0 * ds["alpha"])).assign_attrs(attrs("fits", "alpha_half_width")),
        "gamma_half_width": ((g_upper - g_lower) / 2.0).assign_attrs(attrs("fits", "gamma_half_width")),
    }
    rule = "rule_alpha_half_width" in cube
    flagged = np.zeros(used.shape, np.int8)
    if rule and cube.attrs.get("ensemble") == "adaptive":
        at_cap = counts >= int(cube.attrs["max_realizations"])
        short = ~(cube["rule_alpha_half_width"].transpose(*GRID).values <= float(cube.attrs["rule_target_half_width"]))
        flagged = at_cap & short
    out["flagged"] = xr.DataArray(flagged.astype(np.int8), dims=GRID, attrs=attrs("fits", "flagged"))
    if rule:
        for name in ("rule_alpha_half_width", "rule_gamma_half_width"):
            out[name] = cube[name].transpose(*GRID)
    return out


@single_threaded
def build(scenario: Scenario, cube: xr.Dataset) -> xr.Dataset:
    """Reductions and power-law fits of a resistance cube.

    Parameters
    ----------
    scenario
        Supplies ``fits.*`` and the normalization (material.rho, roughness.sigma,
        indenter.radius).
    cube
        ``resistance`` (xi, lambda, delta, realization) in ohm (+inf = open circuit),
        ``resistance_clean`` (delta), coords ``force`` (N) and ``force_normalized`` on delta.

    Returns
    -------
    xarray.Dataset
        See the module docstring and the variables' attributes.
    """
    resistance = cube["resistance"].transpose(*GRID, "delta", DIM)
    scale = scenario.resistance_scale
    counts, step_counts = _counts(cube), _step_counts(cube)
    ds = _reduce(resistance, counts, scale, step_counts)
    mask = fitted_steps(scenario, cube["force"], cube["force_normalized"])
    force_n = cube["force_normalized"].values
    steps = np.flatnonzero(mask.values)
    control = None
    if scenario.fits.control_variate == "clean_share":
        control = _control(cube)
        _controlled_reduction(ds, resistance.values, control, counts, scale, step_counts)
        control = (control[0][:, :, steps, :], control[1])
    center = ds[f"{scenario.fits.reduction}_normalized"]

    fit = fit_power_law(force_n, center.values, mask.values)
    boot_alpha, boot_gamma, step_band = _bootstrap(
        scenario, resistance.values[:, :, steps, :] / scale, force_n[steps], counts, control,
        None if step_counts is None else step_counts[:, :, steps])
    bound = ("bound", ["lower", "upper"])
    level = f"{100 * scenario.fits.confidence:g} % percentile bootstrap over realizations"

    ds["alpha"] = variable("fits", "alpha", fit.alpha)
    ds["gamma"] = variable("fits", "gamma", fit.gamma)
    for name, boot in (("alpha", boot_alpha), ("gamma", boot_gamma)):
        ds[f"{name}_ci"] = variable("fits", f"{name}_ci", _interval(boot, scenario.fits.confidence), method=level)
    ds = ds.assign_coords(bound=bound[1])
    for name, value in _ensemble_summary(scenario, cube, ds, counts).items():
        ds[name] = value
    if step_counts is not None:
        ds["step_realizations"] = variable("fits", "step_realizations", step_counts.astype(np.int32))
    ds["fit_residual"] = variable("fits", "fit_residual", fit.residual)
    ds["fit_residual_rms"] = variable("fits", "fit_residual_rms", fit.residual_rms)
    ds["n_fitted"] = variable("fits", "n_fitted", fit.n_points)
    ds["fitted"] = mask.astype("int8").assign_attrs(attrs("fits", "fitted", fit_range=range_label(scenario)))
    interval = np.full(center.shape + (2,), np.nan)
    interval[:, :, steps] = step_band
    reduction = {"reduction": scenario.fits.reduction}
    ds[f"{scenario.fits.reduction}_normalized_ci"] = variable("fits", f"{scenario.fits.reduction}_normalized_ci",
                                                              interval, reduction, method=level)
    _curve_vars(ds, fit_curve(force_n, center.values, scenario.fits.curve_tolerance, interval, mask.values,
                              scenario.fits.curve_max_order), "", reduction)

    clean = cube["resistance_clean"]
    ds["resistance_clean"] = clean.assign_attrs(attrs("fits", "resistance_clean"))
    ds["resistance_clean_normalized"] = (clean / scale).assign_attrs(attrs("fits", "resistance_clean_normalized"))
    for name, value in _clean_fit(scenario, (clean / scale).values, force_n, mask.values).items():
        ds[name] = value
    _curve_vars(ds, fit_curve(force_n, (clean / scale).values, scenario.fits.curve_tolerance, None, mask.values,
                              scenario.fits.curve_max_order), "_clean", {})
    ds["resistance_scale"] = variable("fits", "resistance_scale", scale)
    label_coords(ds)
    ds.attrs["reduction"] = scenario.fits.reduction
    ds.attrs["fit_range"] = range_label(scenario)
    ds.attrs["curve_model"] = (
        f"ln R' = sum_k curve_coefficients[k] (ln F')^k; order: the lowest of 1..{scenario.fits.curve_max_order} "
        f"within {100 * scenario.fits.curve_tolerance:g} % at every fitted step, else within "
        f"max({100 * scenario.fits.curve_tolerance:g} %, the step's interval)")
    ds.attrs["normalization"] = "R' = R sqrt(R* sigma)/(2 rho*); F' = 2F/(E* sqrt(R* sigma^3)) (Eq. 25)"
    return ds


def _curve_vars(ds: xr.Dataset, curve: CurveFit, suffix: str, slots: dict[str, str]) -> None:
    """Store a :class:`CurveFit` in ``ds`` as ``curve_*<suffix>`` (and the ``power`` coordinate); ``slots``
    fill the schema's long names (the reduction fitted)."""
    ds.coords["power"] = variable("fits", "power", np.arange(curve.coefficients.shape[-1]))
    ds[f"curve_coefficients{suffix}"] = variable("fits", f"curve_coefficients{suffix}", curve.coefficients, slots)
    ds[f"curve_order{suffix}"] = variable("fits", f"curve_order{suffix}", curve.order.astype(np.int32), slots)
    ds[f"curve_max_error{suffix}"] = variable("fits", f"curve_max_error{suffix}", curve.max_error, slots)
    ds[f"curve_within{suffix}"] = variable("fits", f"curve_within{suffix}", curve.within, slots)
    ds[f"curve_residual{suffix}"] = variable("fits", f"curve_residual{suffix}", curve.residual, slots)


@single_threaded
def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Read ``cube.nc``, fit, write ``fits.nc``; returns the written path.

    ``options`` is accepted for the stage interface; the fits are in-memory numpy work.
    """
    cube = read_stage(data_dir, "cube", scenario, select=_reduced)
    return write_dataset(build(scenario, cube), data_dir, "fits", scenario)


def _reduced(cube: xr.Dataset) -> xr.Dataset:
    """``cube`` without the per-realization variables the fits do not read (:data:`REDUCED`)."""
    return cube.drop_vars([name for name, var in cube.data_vars.items() if DIM in var.dims and name not in REDUCED])
