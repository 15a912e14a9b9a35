"""The variable schema: each output variable's and coordinate's dims, units and long name, declared once.

:data:`SCHEMA` maps every stage file to its variables (the data variables and the coordinates
that carry attributes); a long name may hold ``{field}`` placeholders that the writing stage fills
from its settings (:meth:`Variable.attrs`). The stages, the atlas and the analysis take the
attributes from here; ``tests/fixtures/schema.json`` is the stored list the tests hold it to, and
the end-to-end test holds the written files to it.

Where two files label one coordinate differently today (``xi``: ``nominal oxide fraction`` in
oxide.nc, cube.nc and fits.nc, ``oxide fraction`` in surrogate.nc and the atlas), both labels are
declared, so the files' CF attributes stay as they were.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import xarray as xr

__all__ = ["Variable", "COORDINATES", "SURROGATE_COORDINATES", "RESISTANCE_LONG_NAMES", "SPOT_RADIUS_LONG_NAMES", "SCHEMA", "attrs",
           "variable", "labelled", "array", "matches", "label_coords"]


@dataclass(frozen=True)
class Variable:
    """An output variable: its dimensions, CF units and long name (possibly with ``{field}`` slots)."""

    dims: tuple[str, ...]
    units: str
    long_name: str

    def attrs(self, **fields: Any) -> dict[str, str]:
        """``units`` and ``long_name``, the long name's slots filled from ``fields``."""
        return {"units": self.units, "long_name": self.long_name.format(**fields)}

    @classmethod
    def of(cls, dims: str, units: str, long_name: str) -> "Variable":
        """A variable whose dimensions are written as one space-separated string (``""``: a scalar)."""
        return cls(tuple(dims.split()), units, long_name)

    def pattern(self) -> re.Pattern[str]:
        """A regular expression of the long name, any text in place of each slot."""
        parts = re.split(r"\{\w+\}", self.long_name)
        return re.compile(".+".join(re.escape(p) for p in parts) + r"\Z")


_v = Variable.of


#: The coordinates that several files share, under the label most of them carry.
COORDINATES: dict[str, Variable] = {
    "xi": _v("xi", "1", "nominal oxide fraction"),
    "lambda": _v("lambda", "1", "normalized oxide correlation length l_O sqrt(eta)"),
    "realization": _v("realization", "1", "realization index of the random field"),
    "delta": _v("delta", "m", "approach delta of the sphere tip"),
    "force": _v("delta", "N", "normal force"),
    "force_normalized": _v("delta", "1", "normalized force F' = 2F / (E* sqrt(R* sigma^3))"),
    "quantile": _v("quantile", "1", "quantile over realizations"),
}

#: The labels of the coordinates of the surrogate and the atlas (their xi: see the module docstring).
SURROGATE_COORDINATES: dict[str, Variable] = {
    "xi": _v("xi", "1", "oxide fraction"),
    "lambda": COORDINATES["lambda"],
}

_OXIDE: dict[str, Variable] = {
    "lambda": COORDINATES["lambda"],
    "realization": COORDINATES["realization"],
    "xi": COORDINATES["xi"],
    "y": _v("y", "m", "cell-centre y coordinate from the axis"),
    "x": _v("x", "m", "cell-centre x coordinate from the axis"),
    "correlation_length": _v("lambda", "m", "oxide correlation length l_O = pi / k1"),
    "psi": _v("lambda realization y x", "1", "unit-variance Gaussian random field at the cell centres"),
    "threshold": _v("xi lambda realization", "1", "threshold psi0 used for each field"),
    "oxide_fraction": _v("xi lambda realization", "1", "realized oxide-covered fraction of the cell centres"),
    "n_modes": _v("lambda", "1", "independent Fourier modes (Hermitian pairs) in the band k1..ks"),
    "period_cells": _v("lambda", "1", "period of the random field, in cells"),
}

_CONTACT: dict[str, Variable] = {
    "area_fraction": _v("delta r", "1", "real contact area fraction A* (Eq. 21 with the 1/2)"),
    "barber_conductance": _v("delta", "S", "Barber's conductance K / (E* rho*) of the clean elastic contact (Eq. 1)"),
    "converged": _v("delta", "1", "1 if the solver met its tolerance"),
    "delta": _v("delta", "m", "initial separation of the tip from the mean plane (negative: interpenetration)"),
    "delta_sigma": _v("delta", "1", "approach delta / sigma"),
    "displacement": _v("delta r", "m", "total elastic normal displacement of both surfaces (Eq. 18)"),
    "force": _v("delta", "N", "normal force 2 pi integral p r dr"),
    "force_normalized": _v("delta", "1", "normalized force 2F / (E* sqrt(R* sigma^3)) (Eq. 25)"),
    "hertz_displacement": _v("delta r", "m", "Hertz displacement at the same force"),
    "hertz_pressure": _v("delta r", "Pa", "Hertz pressure at the same force"),
    "hertz_radius": _v("delta", "m", "Hertz contact radius at the same force"),
    "hertz_separation": _v("delta r", "m", "Hertz gap between the deformed surfaces"),
    "holm_radius": _v("delta", "m", "Holm-Greenwood radius alpha_HG of all spots (Eq. 13)"),
    "iterations": _v("delta", "1", "{solver} iterations"),
    "pressure": _v("delta r", "Pa", "mean asperity contact pressure (Eq. 16)"),
    "profile": _v("r", "m", "undeformed indenter profile ({shape})"),
    "r": _v("r", "m", "radial coordinate"),
    "residual": _v("delta", "1", "final relative residual max|u - M p(u)| / max|M p(u)|"),
    "roughness_parameter": _v("delta", "1", "roughness parameter sigma R* / a^2"),
    "separation": _v("delta r", "m", "separation of the mean planes, delta + profile + displacement"),
    "spot_area": _v("delta y x", "m2", "cell contact area A*(r_i) dx^2"),
    "spot_radius": _v("delta y x", "m", "{spot_radius}"),
    "spot_separation": _v("delta y x", "m", "separation of the mean planes at the cell centre"),
    "stiffness": _v("delta", "N m-1",
              "contact stiffness K = -dF/d delta (exact linearisation of the discretised Greenwood-Tripp system)"),
    "x": _v("x", "m", "cell centre x"),
    "y": _v("y", "m", "cell centre y"),
    # contact.model = "discrete": the pool of surfaces (g2tom.stages.contact_discrete)
    "surface": _v("surface", "1", "rough surface of the pool"),
    "spot": _v("spot", "1", "touching asperity of a surface"),
    "spot_count": _v("surface", "1", "asperities of the surface that touch at some load step"),
    "surface_steps": _v("surface", "1", "load steps the surface was solved at, the lightest first (a grown pool)"),
    "asperity_x": _v("surface spot", "m", "touching asperity position x (from the indenter's axis)"),
    "asperity_y": _v("surface spot", "m", "touching asperity position y (from the indenter's axis)"),
    "asperity_radius": _v("surface delta spot", "m", "contact radius sqrt(beta w) of the touching asperity (0 off contact)"),
    "discrete_approach": _v("surface delta", "m",
                            "approach of the discrete surface at the step's force (tip's separation from the mean plane)"),
    "discrete_stiffness": _v("surface delta", "N m-1",
                             "contact stiffness K = -dF/d delta of the discrete surface (exact linearisation)"),
    "discrete_barber_conductance": _v("surface delta", "S", "Barber's conductance K / (E* rho*) of the discrete surface"),
    "discrete_iterations": _v("surface delta", "1", "Newton iterations of the discrete solve"),
    "discrete_residual": _v("surface delta", "1", "final relative residual of the discrete solve"),
    "discrete_candidates": _v("surface delta", "1", "candidate asperities in the discrete solve"),
}

_CUBE: dict[str, Variable] = {
    "clean_share": _v("xi lambda delta realization", "1",
              "the spots' clean shares averaged with their contact radii (the control variate)"),
    "clean_share_expected": _v("xi lambda", "1",
              "probability that a point of the field is clean: the expectation of clean_share"),
    "clean_open_probability": _v("delta", "1",
              "probability that the oxide-free surface is an open circuit (no touching asperity)"),
    "conductance_clean": _v("delta", "S", "conductance of the oxide-free surface ({model} model)"),
    "conductance_clean_greenwood": _v("delta", "S", "conductance of the oxide-free surface by the greenwood model"),
    "conductance_clean_point": _v("delta", "S", "conductance of the oxide-free surface by the point model"),
    "conductance_clean_point_lattice": _v("delta", "S",
              "conductance of the oxide-free surface by the point + lattice model"),
    "crop_cells": _v("delta", "1", "side of the centred square of cells kept at each approach"),
    "delta": COORDINATES["delta"],
    "force": COORDINATES["force"],
    "force_normalized": COORDINATES["force_normalized"],
    "lambda": COORDINATES["lambda"],
    "n_conducting": _v("xi lambda delta realization", "1", "number of conducting spots"),
    "n_open": _v("xi lambda delta", "1", "number of open-circuit realizations (R = +inf)"),
    "n_realizations": _v("xi lambda", "1",
              "realizations used at this (xi, lambda): the leading entries of realization"),
    "realization": COORDINATES["realization"],
    "resistance": _v("xi lambda delta realization", "ohm", "{resistance}"),
    "iterations": _v("xi lambda delta realization", "1", "conjugate-gradient iterations of the point-model solve"),
    "residual": _v("xi lambda delta realization", "1", "final relative residual of the point-model solve (Jacobi norm)"),
    "error_estimate": _v("xi lambda delta realization", "1",
                         "estimated relative error of the point-model conductance (energy norm of the last step)"),
    "resistance_clean": _v("delta", "ohm", "resistance of the oxide-free surface"),
    "resistance_clean_interaction": _v("delta", "ohm", "interaction term of the oxide-free surface"),
    "resistance_clean_self": _v("delta", "ohm", "self term of the oxide-free surface"),
    "resistance_interaction": _v("xi lambda delta realization", "ohm",
              "interaction term rho* sum phi phi w w / d / (pi (sum phi w)^2), w in {weights_unit}"),
    "resistance_self": _v("xi lambda delta realization", "ohm", "self term rho* / (2 sum phi a)"),
    "rule_alpha_half_width": _v("xi lambda", "1", "fast-rule relative half-width of alpha at n_realizations"),
    "rule_gamma_half_width": _v("xi lambda", "1", "fast-rule absolute half-width of gamma at n_realizations"),
    "step_realizations": _v("xi lambda delta", "1",
              "realizations used at this (xi, lambda) and load step: the leading entries of realization"),
    "xi": COORDINATES["xi"],
}

_FITS: dict[str, Variable] = {
    "alpha": _v("xi lambda", "1", "alpha of R' = alpha F'^-gamma"),
    "alpha_ci": _v("xi lambda bound", "1", "confidence interval of alpha"),
    "alpha_clean": _v("", "1", "alpha of the clean surface"),
    "alpha_clean_ci": _v("bound", "1", "confidence interval of alpha_clean"),
    "alpha_half_width": _v("xi lambda", "1",
              "relative half-width of the alpha interval, (upper - lower) / (2 alpha)"),
    "arithmetic_mean": _v("xi lambda delta", "ohm", "arithmetic mean of R over realizations"),
    "arithmetic_mean_normalized": _v("xi lambda delta", "1", "arithmetic mean of R' = R sqrt(R* sigma)/(2 rho*)"),
    "curve_coefficients": _v("xi lambda power", "1",
              "coefficients c_k of ln R' = sum_k c_k (ln F')^k fitted to the {reduction} of R'"),
    "curve_coefficients_clean": _v("power", "1",
              "coefficients c_k of ln R' = sum_k c_k (ln F')^k fitted to the clean-surface R'"),
    "curve_max_error": _v("xi lambda", "1",
              "largest relative error |R'_curve / R' - 1| over the fitted steps of the {reduction} of R'"),
    "curve_max_error_clean": _v("", "1",
              "largest relative error |R'_curve / R' - 1| over the fitted steps of the clean-surface R'"),
    "curve_order": _v("xi lambda", "1", "order of the curve model of the {reduction} of R' (0: not fitted)"),
    "curve_order_clean": _v("", "1", "order of the curve model of the clean-surface R' (0: not fitted)"),
    "curve_residual": _v("xi lambda delta", "1",
              "ln R'_curve - ln R' of the {reduction} of R' on the fitted steps"),
    "curve_residual_clean": _v("delta", "1", "ln R'_curve - ln R' of the clean-surface R' on the fitted steps"),
    "curve_within": _v("xi lambda", "1",
              "where the curve of the {reduction} of R' is at every fitted step: 1 within the relative tolerance, 2 within max(tolerance, the step's interval) only, 0 neither"),
    "curve_within_clean": _v("", "1",
              "where the curve of the clean-surface R' is at every fitted step: 1 within the relative tolerance, 2 within max(tolerance, the step's interval) only, 0 neither"),
    "delta": COORDINATES["delta"],
    "fit_residual": _v("xi lambda delta", "1", "log(R') - log(alpha F'^-gamma) on the fitted steps"),
    "fit_residual_clean": _v("delta", "1", "log residual of the clean fit"),
    "fit_residual_rms": _v("xi lambda", "1", "RMS of the log residuals"),
    "fit_residual_rms_clean": _v("", "1", "RMS log residual of the clean fit"),
    "fitted": _v("delta", "1", "1 where the step was fitted ({fit_range})"),
    "flagged": _v("xi lambda", "1",
              "1 where the adaptive ensemble stopped at max_realizations short of the target half-width"),
    "force": COORDINATES["force"],
    "force_normalized": COORDINATES["force_normalized"],
    "gamma": _v("xi lambda", "1", "gamma of R' = alpha F'^-gamma"),
    "gamma_ci": _v("xi lambda bound", "1", "confidence interval of gamma"),
    "gamma_clean": _v("", "1", "gamma of the clean surface"),
    "gamma_clean_ci": _v("bound", "1", "confidence interval of gamma_clean"),
    "gamma_half_width": _v("xi lambda", "1", "absolute half-width of the gamma interval, (upper - lower) / 2"),
    "control_variate_applied": _v("xi lambda delta", "1",
              "1 where the geometric mean is the control-variate estimate, else 0 (the plain mean)"),
    "geometric_mean": _v("xi lambda delta", "ohm", "geometric mean of R over realizations"),
    "geometric_mean_normalized": _v("xi lambda delta", "1", "geometric mean of R' = R sqrt(R* sigma)/(2 rho*)"),
    "arithmetic_mean_normalized_ci": _v("xi lambda delta bound", "1",
              "confidence interval of the {reduction} of R' at each fitted step"),
    "geometric_mean_normalized_ci": _v("xi lambda delta bound", "1",
              "confidence interval of the {reduction} of R' at each fitted step"),
    "median_normalized_ci": _v("xi lambda delta bound", "1",
              "confidence interval of the {reduction} of R' at each fitted step"),
    "lambda": COORDINATES["lambda"],
    "median": _v("xi lambda delta", "ohm", "median of R over realizations"),
    "median_normalized": _v("xi lambda delta", "1", "median of R' = R sqrt(R* sigma)/(2 rho*)"),
    "n_fitted": _v("xi lambda", "1", "finite fitted steps"),
    "n_realizations": _v("xi lambda", "1", "realizations used per (xi, lambda)"),
    "open_probability": _v("xi lambda delta", "1", "share of realizations with no conducting spot (R = inf)"),
    "power": _v("power", "1", "power k of ln F' in the curve model"),
    "quantile": COORDINATES["quantile"],
    "resistance_clean": _v("delta", "ohm", "clean-surface resistance"),
    "resistance_clean_normalized": _v("delta", "1", "clean-surface R'"),
    "resistance_quantile": _v("xi lambda delta quantile", "ohm", "resistance quantile of R over realizations"),
    "resistance_quantile_normalized": _v("xi lambda delta quantile", "1",
              "resistance quantile of R' = R sqrt(R* sigma)/(2 rho*)"),
    "resistance_scale": _v("", "ohm", "2 rho*/sqrt(R* sigma): R' = R / resistance_scale"),
    "rule_alpha_half_width": _v("xi lambda", "1", "fast-rule relative half-width of alpha at n_realizations"),
    "rule_gamma_half_width": _v("xi lambda", "1", "fast-rule absolute half-width of gamma at n_realizations"),
    "step_realizations": _v("xi lambda delta", "1",
              "realizations used at this (xi, lambda) and load step: the leading entries of realization"),
    "xi": COORDINATES["xi"],
}

_SURROGATE: dict[str, Variable] = {
    "alpha_clean": _v("", "1", "alpha of the clean surface"),
    "alpha_clean_ci": _v("bound", "1", "confidence interval of alpha_clean"),
    "alpha_coef_w": _v("alpha_mode alpha_power_w", "1",
              "{transformed}: mode polynomials in w = log(lambda), ascending powers"),
    "alpha_coef_z": _v("alpha_mode alpha_power_z", "1",
              "{transformed}: mode polynomials in z = -log(1 - xi), ascending powers"),
    "alpha_cv_error": _v("lambda xi", "1", "local leave-one-line-out RMS error of ln alpha"),
    "alpha_cv_free_parameters": _v("alpha_candidate", "1", "alpha candidates: free parameters r (p + q - r)"),
    "alpha_cv_order_w": _v("alpha_candidate", "1", "alpha candidates: order in w"),
    "alpha_cv_order_z": _v("alpha_candidate", "1", "alpha candidates: order in z"),
    "alpha_cv_rank": _v("alpha_candidate", "1", "alpha candidates: rank r"),
    "alpha_cv_rms": _v("alpha_candidate", "1",
              "alpha: leave-one-line-out RMS relative error of each candidate model"),
    "alpha_cv_transform": _v("alpha_candidate", "1", "alpha candidates: transform T"),
    "alpha_fit": _v("lambda xi", "1", "fitted alpha"),
    "alpha_fit_sigma": _v("lambda xi", "1", "one standard deviation of ln alpha from the fit's interval"),
    "alpha_loo": _v("order_w order_z", "1", "leave-one-line-out RMS relative error of alpha"),
    "alpha_mode_lambda": _v("alpha_mode lambda", "1", "alpha: SVD modes u_k(lambda) = sqrt(s_k) U_k"),
    "alpha_mode_xi": _v("alpha_mode xi", "1", "alpha: SVD modes v_k(xi) = sqrt(s_k) V_k"),
    "alpha_relative_error": _v("lambda xi", "1", "surrogate / fitted alpha - 1"),
    "alpha_singular_values": _v("component", "1", "alpha: all singular values of the grid matrix"),
    "alpha_surrogate": _v("lambda xi", "1", "surrogate alpha"),
    "band_ratio_lower": _v("lambda xi step", "1", "R'_16 / R'_center"),
    "band_ratio_upper": _v("lambda xi step", "1", "R'_center / R'_84 (0: R_84 = inf)"),
    "curve_coefficients": _v("lambda xi power", "1",
              "curve model: ln R' = sum_k c_k (ln F')^k of each cell (fits.nc)"),
    "curve_fit_error": _v("lambda xi step", "1",
              "one standard deviation of ln R' of the cell's mean curve at each fitted step"),
    "curve_interpolation_error": _v("lambda xi", "1",
              "leave-one-out error of ln R' interpolated linearly in (ln lambda, -ln(1 - xi))"),
    "force": _v("step", "N", "normal force"),
    "force_normalized": _v("step", "1", "F' = 2F/(E* sqrt(R* sigma^3))"),
    "force_normalized_range": _v("end", "1", "fitted range of force_normalized"),
    "gamma_clean": _v("", "1", "gamma of the clean surface"),
    "gamma_clean_ci": _v("bound", "1", "confidence interval of gamma_clean"),
    "gamma_coef_w": _v("gamma_mode gamma_power_w", "1",
              "{transformed}: mode polynomials in w = log(lambda), ascending powers"),
    "gamma_coef_z": _v("gamma_mode gamma_power_z", "1",
              "{transformed}: mode polynomials in z = -log(1 - xi), ascending powers"),
    "gamma_cv_error": _v("lambda xi", "1", "local leave-one-line-out RMS error of gamma"),
    "gamma_cv_free_parameters": _v("gamma_candidate", "1", "gamma candidates: free parameters r (p + q - r)"),
    "gamma_cv_order_w": _v("gamma_candidate", "1", "gamma candidates: order in w"),
    "gamma_cv_order_z": _v("gamma_candidate", "1", "gamma candidates: order in z"),
    "gamma_cv_rank": _v("gamma_candidate", "1", "gamma candidates: rank r"),
    "gamma_cv_rms": _v("gamma_candidate", "1",
              "gamma: leave-one-line-out RMS relative error of each candidate model"),
    "gamma_cv_transform": _v("gamma_candidate", "1", "gamma candidates: transform T"),
    "gamma_fit": _v("lambda xi", "1", "fitted gamma"),
    "gamma_fit_sigma": _v("lambda xi", "1", "one standard deviation of gamma from the fit's interval"),
    "gamma_loo": _v("order_w order_z", "1", "leave-one-line-out RMS relative error of gamma"),
    "gamma_mode_lambda": _v("gamma_mode lambda", "1", "gamma: SVD modes u_k(lambda) = sqrt(s_k) U_k"),
    "gamma_mode_xi": _v("gamma_mode xi", "1", "gamma: SVD modes v_k(xi) = sqrt(s_k) V_k"),
    "gamma_relative_error": _v("lambda xi", "1", "surrogate / fitted gamma - 1"),
    "gamma_singular_values": _v("component", "1", "gamma: all singular values of the grid matrix"),
    "gamma_surrogate": _v("lambda xi", "1", "surrogate gamma"),
    "lambda": SURROGATE_COORDINATES["lambda"],
    "lambda_range": _v("end", "1", "fitted range of lambda"),
    "open_probability": _v("lambda xi step", "1", "share of open-circuit realizations"),
    "order_w": _v("order_w", "1", "polynomial order in w tried by cross-validation"),
    "order_z": _v("order_z", "1", "polynomial order in z tried by cross-validation"),
    "xi": SURROGATE_COORDINATES["xi"],
    "xi_range": _v("end", "1", "fitted range of xi"),
}

#: The long name of contact.nc's ``spot_radius`` by ``contact.spots`` (its ``{spot_radius}`` slot).
SPOT_RADIUS_LONG_NAMES = {
    "mean_area": "spot radius sqrt(A_i / pi) (mean_area spots)",
    "expected": "spot radius sqrt(beta) F_1/2(h): expected sum of asperity radii in the cell (expected spots)",
    "asperities": "mean spot radius sqrt(beta) F_1/2(h) over realizations (asperity spots are drawn in the cube)",
}

#: The long name of the cube's ``resistance`` by ``cube.model`` (its ``{resistance}`` slot).
RESISTANCE_LONG_NAMES = {
    "greenwood": "Greenwood constriction resistance R = R_self + R_int",
    "point": "point-interaction constriction resistance R = rho* / sum f (exact solve of M f = 1)",
}

#: Every stage file's variables and labelled coordinates.
SCHEMA: dict[str, dict[str, Variable]] = {
    "contact": _CONTACT, "oxide": _OXIDE, "cube": _CUBE, "fits": _FITS, "surrogate": _SURROGATE,
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
