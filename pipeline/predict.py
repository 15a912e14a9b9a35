"""The phenomenological predictor of Eq. 27 and its error band, from a fitted surrogate.

    R_el = alpha(xi, lambda) 2 rho* / sqrt(R* sigma) F'^-gamma(xi, lambda),
    F' = 2 F / (E* sqrt(R* sigma^3)),   E* = E / (2 (1 - nu^2)),

with ``T(p) = sum_k P_k(w) Q_k(z)``, w = log(lambda), z = -log(1 - xi), T = log or identity
(the surrogate stage's model). Material (E, nu, rho*), roughness (sigma) and indenter (R*)
come from the scenario.

The band carries three errors, each as a one-standard-deviation half-width in ln R (a
relative error), interpolated linearly in (w, z[, ln F']) from the grid tables of the
surrogate stage and clamped to the grid:

* ``spread_lower`` = -ln(R'_16 / R'_c), ``spread_upper`` = ln(R'_84 / R'_c): the spread of
  single realizations (16-84 %, +inf above when more than 16 % are open circuits);
* ``fit_error`` = sqrt(s_a^2 + (ln F' s_g)^2), s_a and s_g one standard deviation of ln alpha
  and gamma from the fits' confidence intervals ((upper - lower) / (2 z_c));
* ``surrogate_error`` = sqrt(e_a^2 + (ln F' e_g)^2), e_a and e_g the local leave-one-line-out
  RMS errors of ln alpha and gamma.

The errors are taken as independent (the fits stage stores no covariance of alpha and gamma)
and combined in quadrature, on each side:

    total_lower = sqrt(spread_lower^2 + fit_error^2 + surrogate_error^2),
    lower = R exp(-total_lower),  upper = R exp(+total_upper).

A component that is unknown (NaN: e.g. a grid too small to cross-validate) is left out of the
total, and a warning says so. Queries outside the fitted ranges of xi, lambda or F' are refused
unless ``extrapolate=True`` (then an :class:`ExtrapolationWarning`); where the local surrogate
error exceeds ``warn_error`` a :class:`SurrogateErrorWarning` is issued.

The predictor works from ``surrogate.json`` alone (:meth:`SurrogateTables.to_json`: the
coefficients, coordinate maps, scale conventions, fitted ranges and band tables) and gives the
same numbers from ``surrogate.nc``.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import xarray as xr
from scipy.interpolate import RegularGridInterpolator

from pipeline.config import ConfigError, Scenario
from pipeline.physics.curve_model import evaluate_curve
from pipeline.physics.surrogate import evaluate, to_w, to_z
from pipeline.predict_domain import answered_by, check_surface, with_measured_roughness
from pipeline.stages.surrogate import scene_groups

__all__ = [
    "ExtrapolationWarning",
    "SurrogateErrorWarning",
    "SurrogateTables",
    "load_surrogate",
    "predict",
    "predict_cli",
    "OUTPUT_COLUMNS",
    "to_csv",
]

FORMAT = "g2tom-surrogate"
VERSION = 1
PARAMETERS = ("alpha", "gamma")
#: Per-cell (lambda, xi) tables and per-step (lambda, xi, step) tables the band needs.
GRID_TABLES = ("alpha_fit_sigma", "gamma_fit_sigma", "alpha_cv_error", "gamma_cv_error", "curve_interpolation_error")
STEP_TABLES = ("band_ratio_lower", "band_ratio_upper", "open_probability", "curve_fit_error")
#: The curve model's coefficients, (lambda, xi, power).
CURVE_TABLE = "curve_coefficients"
#: What :func:`predict` can answer with: the curve model (default) or Eq. 27's power law.
MODELS = ("curve", "power_law")
RANGES = ("xi", "lambda", "force_normalized")


class ExtrapolationWarning(UserWarning):
    """xi, lambda or F' lies outside the range the surrogate was fitted on."""


class SurrogateErrorWarning(UserWarning):
    """The surrogate's local cross-validated error exceeds the warning threshold."""


@dataclass(frozen=True)
class SurrogateTables:
    """Everything the predictor needs, as plain numpy arrays.

    Attributes
    ----------
    coef
        Parameter name -> (coef_w (rank, p), coef_z (rank, q), transform).
    lam, xi
        The fitted grid (dimensionless).
    force_normalized
        F' of the fitted load steps (dimensionless).
    ranges
        ``xi``, ``lambda``, ``force_normalized`` -> (min, max) fitted.
    tables
        :data:`GRID_TABLES` (lambda, xi) and :data:`STEP_TABLES` (lambda, xi, step), dimensionless.
    info
        Provenance and model description (method, formulas, free parameters, CV errors).
    """

    coef: dict[str, tuple[np.ndarray, np.ndarray, str]]
    lam: np.ndarray
    xi: np.ndarray
    force_normalized: np.ndarray
    ranges: dict[str, tuple[float, float]]
    tables: dict[str, np.ndarray]
    info: dict[str, Any]

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> "SurrogateTables":
        """From ``surrogate.nc`` (or the surrogate stage's dataset)."""
        missing = [n for n in (*(f"{p}_coef_w" for p in PARAMETERS), *GRID_TABLES, *STEP_TABLES, CURVE_TABLE) if n not in ds]
        if missing:
            raise ConfigError(f"the surrogate dataset lacks {', '.join(missing)}: re-run `g2tom surrogate`")
        coef = {p: (ds[f"{p}_coef_w"].values, ds[f"{p}_coef_z"].values, str(ds[f"{p}_coef_w"].attrs.get("transform", "identity")))
                for p in PARAMETERS}
        tables = {n: ds[n].transpose("lambda", "xi").values for n in GRID_TABLES}
        tables.update({n: ds[n].transpose("lambda", "xi", "step").values for n in STEP_TABLES})
        tables[CURVE_TABLE] = ds[CURVE_TABLE].transpose("lambda", "xi", "power").values
        info = {k: _plain(ds.attrs[k]) for k in _INFO_KEYS if k in ds.attrs}
        return cls(
            coef=coef,
            lam=ds["lambda"].values,
            xi=ds["xi"].values,
            force_normalized=ds["force_normalized"].values,
            ranges={r: (float(ds[f"{r}_range"][0]), float(ds[f"{r}_range"][1])) for r in RANGES},
            tables=tables,
            info=info,
        )

    def to_json(self) -> str:
        """The ``surrogate.json`` text (NaN written as null, infinities as "inf"; floats round-trip exactly)."""
        doc = {
            "format": FORMAT,
            "version": VERSION,
            "model": {
                "predictor": "curve (default): R_el = 2 rho* / sqrt(R* sigma) * exp(sum_k c_k (ln F')^k), c_k = "
                             "tables.curve_coefficients[lambda][xi][k] interpolated linearly in (w, z); "
                             "power_law: R_el = alpha * 2 rho* / sqrt(R* sigma) * F'^(-gamma)  (Eq. 27)",
                "surrogate": "T(p) = sum_k P_k(w) Q_k(z), P_k(w) = sum_i coef_w[k][i] w^i, "
                             "Q_k(z) = sum_j coef_z[k][j] z^j; T = log (p = exp(...)) or identity",
                "coordinates": {"w": "ln(lambda), lambda = l_O sqrt(eta)", "z": "-ln(1 - xi)"},
                "scales": {
                    "F'": "2 F / (E* sqrt(R* sigma^3)), F in N",
                    "R'": "R_el sqrt(R* sigma) / (2 rho*), R_el in ohm",
                    "E*": "E / (2 (1 - nu^2)), Pa",
                },
                "band": "ln-R half-widths (one standard deviation) combined in quadrature: "
                        "total = sqrt(spread^2 + fit_error^2 + surrogate_error^2), lower = R exp(-total_lower), "
                        "upper = R exp(total_upper); see pipeline.predict",
            },
            "parameters": {
                p: {"transform": t, "coef_w": cw.tolist(), "coef_z": cz.tolist()} for p, (cw, cz, t) in self.coef.items()
            },
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "grid": {"lambda": self.lam.tolist(), "xi": self.xi.tolist(), "force_normalized": self.force_normalized.tolist()},
            "tables": {k: _encode(v) for k, v in self.tables.items()},
            "info": self.info,
        }
        return json.dumps(doc, indent=1, allow_nan=False) + "\n"

    @classmethod
    def from_json(cls, text: str, source: str = "surrogate.json") -> "SurrogateTables":
        """Parse :meth:`to_json` output; ConfigError if it is not a surrogate file."""
        try:
            doc = json.loads(text)
            if doc.get("format") != FORMAT:
                raise ValueError(f"format is {doc.get('format')!r}, not {FORMAT!r}")
            coef = {p: (np.array(doc["parameters"][p]["coef_w"], dtype=float), np.array(doc["parameters"][p]["coef_z"], dtype=float),
                        str(doc["parameters"][p]["transform"])) for p in PARAMETERS}
            tables = {k: np.array(_decode(doc["tables"][k]), dtype=float) for k in (*GRID_TABLES, *STEP_TABLES, CURVE_TABLE)}
            grid = doc["grid"]
            return cls(
                coef=coef,
                lam=np.array(grid["lambda"], dtype=float),
                xi=np.array(grid["xi"], dtype=float),
                force_normalized=np.array(grid["force_normalized"], dtype=float),
                ranges={k: (float(doc["ranges"][k][0]), float(doc["ranges"][k][1])) for k in RANGES},
                tables=tables,
                info=doc.get("info", {}),
            )
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise ConfigError(f"--surrogate {source!r} is not a g2tom surrogate.json ({exc})") from None

    # ------------------------------------------------------------------ evaluation
    def parameter(self, name: str, lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """Surrogate alpha or gamma at (lambda, xi)."""
        coef_w, coef_z, transform = self.coef[name]
        return evaluate(coef_w, coef_z, lam, xi, transform)

    def curve(self, lam: np.ndarray, xi: np.ndarray, force_n: np.ndarray) -> np.ndarray:
        """ln R' of the curve model: each cell's coefficients interpolated linearly in (w, z),
        clamped to the grid (exact at the grid's cells), evaluated at ``force_n``."""
        coef = self.interpolate((CURVE_TABLE,), lam, xi)[..., 0]  # (n, power)
        return evaluate_curve(coef, force_n[:, None])[:, 0]

    def interpolate(self, names: tuple[str, ...], lam: np.ndarray, xi: np.ndarray, force_n: np.ndarray | None = None) -> np.ndarray:
        """Tables linearly interpolated in (w, z[, ln F']), clamped to the grid; shape (n, len(names))
        (tables with trailing axes beyond (lambda, xi[, step]) keep them after the query axis)."""
        axes = [to_w(self.lam), to_z(self.xi)]
        points = [to_w(lam), to_z(xi)]
        if force_n is not None:
            axes.append(np.log(self.force_normalized))
            points.append(np.log(force_n))
        values = np.stack([self.tables[n] for n in names], axis=-1)
        keep = [a.size > 1 for a in axes]
        values = values[tuple(slice(None) if k else 0 for k in keep)]
        points = [np.clip(p, a.min(), a.max()) for p, a, k in zip(points, axes, keep) if k]
        axes = [a for a, k in zip(axes, keep) if k]
        if not axes:
            return np.broadcast_to(values, (lam.size, len(names))).copy()
        return RegularGridInterpolator(tuple(axes), values)(np.stack(points, axis=-1))


_INFO_KEYS = (
    "scenario", "config_hash", "method", "reduction", "fit_confidence", "mu", "Pi", "indenter_shape",
    *(f"{p}_{k}" for p in PARAMETERS for k in ("transform", "rank", "order_w", "order_z", "free_parameters", "cv_rms", "formula")),
)


def _plain(value: Any) -> Any:
    """A netCDF attribute as a JSON-ready Python value."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _encode(a: np.ndarray) -> list:
    """Nested lists for JSON: NaN as null, +-inf as the strings "inf" / "-inf"."""
    out = a.astype(object)
    out[np.isnan(a)] = None
    out[np.isposinf(a)] = "inf"
    out[np.isneginf(a)] = "-inf"
    return out.tolist()


def _decode(values: Any) -> Any:
    """Inverse of :func:`_encode`."""
    if isinstance(values, list):
        return [_decode(v) for v in values]
    if values is None:
        return math.nan
    return float(values) if isinstance(values, str) and values in ("inf", "-inf") else values


def load_surrogate(path: str | Path) -> SurrogateTables:
    """Load ``surrogate.json`` (no netCDF needed) or ``surrogate.nc``.

    Raises
    ------
    ConfigError
        If the file is missing or is not a surrogate file.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"--surrogate {str(path)!r} does not exist: run `g2tom surrogate` (or `make surrogate`) first")
    if path.suffix == ".json":
        return SurrogateTables.from_json(path.read_text(), str(path))
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise ConfigError(f"--surrogate {str(path)!r} is not a readable netCDF file ({exc})") from None
    return SurrogateTables.from_dataset(ds)


# --------------------------------------------------------------------------- queries
def _queries(force: Any, xi: Any, lam: Any) -> tuple[list[np.ndarray], Callable[[np.ndarray], Any]]:
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


def _check_values(force: np.ndarray, xi: np.ndarray, lam: np.ndarray) -> None:
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
        :data:`pipeline.predict_domain.GROUP_TOLERANCE` (relative) and
        ``extrapolate`` is False.

    Warns
    -----
    ExtrapolationWarning, SurrogateErrorWarning
    """
    if model not in MODELS:
        raise ConfigError(f"model = {model!r} is not allowed: must be one of {', '.join(MODELS)}")
    tables = surrogate if isinstance(surrogate, SurrogateTables) else SurrogateTables.from_dataset(surrogate)
    (f, x, lm), label = _queries(force, xi, lam)
    _check_values(f, x, lm)
    check_surface(tables, scenario, extrapolate)
    force_n = f / scenario.force_scale
    check_ranges(tables.ranges, {"xi": x, "lambda": lm, "force_normalized": force_n}, extrapolate)
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
    _warn_components(fit_error, surrogate_error, lm, x)
    threshold = scenario.surrogate.warn_error if warn_error is None else warn_error
    _warn_surrogate_error(surrogate_error, threshold, lm, x, force_n)
    total_lower = _quadrature(spread_lower, fit_error, surrogate_error)
    total_upper = _quadrature(spread_upper, fit_error, surrogate_error)
    columns = {
        "force": f, "xi": x, "lambda": lm, "force_normalized": force_n, "alpha": alpha, "gamma": gamma,
        "resistance": resistance, "lower": resistance * np.exp(-total_lower), "upper": resistance * np.exp(total_upper),
        "realization_lower": resistance * np.exp(-spread_lower), "realization_upper": resistance * np.exp(spread_upper),
        "spread_lower": spread_lower, "spread_upper": spread_upper, "fit_error": fit_error,
        "surrogate_error": surrogate_error, "total_lower": total_lower, "total_upper": total_upper,
        "open_probability": open_p, "resistance_curve": curve, "resistance_power_law": power_law,
        "mu": np.full(f.size, scene_groups(scenario).mu), "Pi": np.full(f.size, scene_groups(scenario).Pi),
    }
    ds = xr.Dataset({name: label(values) for name, values in columns.items()})
    for name, (units, long_name) in OUTPUT_COLUMNS.items():
        ds[name].attrs = {"units": units, "long_name": long_name}
    ds.attrs["band"] = "total = sqrt(spread^2 + fit_error^2 + surrogate_error^2) per side; lower = R exp(-total_lower), upper = R exp(total_upper)"
    ds.attrs["surrogate_method"] = str(tables.info.get("method", "unknown"))
    ds.attrs["model"] = model
    ds.attrs["answered_by"] = answered_by(tables)
    return ds


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


# --------------------------------------------------------------------------- CLI
def _parse_list(option: str, text: str) -> np.ndarray:
    items = [t.strip() for t in text.split(",")]
    try:
        return np.array([float(t) for t in items])
    except ValueError:
        raise ConfigError(f"{option} = {text!r} is not a number or a comma-separated list of numbers") from None


def _cli_queries(args: argparse.Namespace) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(force, xi, lambda) from --force/--xi/--lambda lists or --csv, checked."""
    options = {"--force": args.force, "--xi": args.xi, "--lambda": args.lam}
    if args.csv is not None:
        if any(v is not None for v in options.values()):
            raise ConfigError("--csv cannot be combined with --force, --xi or --lambda: give the queries one way")
        return _read_csv(Path(args.csv))
    missing = [k for k, v in options.items() if v is None]
    if missing:
        raise ConfigError(f"{', '.join(missing)} missing: give --force, --xi and --lambda (comma-separated lists) or --csv FILE")
    values = [_parse_list(k, v) for k, v in options.items()]
    sizes = {v.size for v in values} - {1}
    if len(sizes) > 1:
        counts = ", ".join(f"{k} {v.size}" for k, v in zip(options, values))
        raise ConfigError(f"lists of different lengths ({counts}): give one value or the same number of values for each")
    n = max(v.size for v in values)
    return tuple(np.broadcast_to(v, (n,)).copy() for v in values)  # type: ignore[return-value]


def _read_csv(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns force, xi, lambda of a CSV file with a header line (other columns ignored)."""
    if not path.is_file():
        raise ConfigError(f"--csv {str(path)!r} does not exist")
    try:
        rows = list(csv.reader(io.StringIO(path.read_text())))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ConfigError(f"--csv {str(path)!r} is not a readable CSV file ({exc})") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if len(rows) < 2:
        raise ConfigError(f"--csv {str(path)!r} needs a header line (force,xi,lambda) and at least one query")
    header = [c.strip().lower() for c in rows[0]]
    missing = [c for c in ("force", "xi", "lambda") if c not in header]
    if missing:
        raise ConfigError(f"--csv {str(path)!r}: header {rows[0]!r} lacks column(s) {', '.join(missing)} (need force, xi, lambda)")
    index = [header.index(c) for c in ("force", "xi", "lambda")]
    out = np.empty((3, len(rows) - 1))
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ConfigError(f"--csv {str(path)!r} line {line}: {len(row)} fields, the header has {len(header)}")
        for k, (name, i) in enumerate(zip(("force", "xi", "lambda"), index)):
            try:
                out[k, line - 2] = float(row[i])
            except ValueError:
                raise ConfigError(f"--csv {str(path)!r} line {line}: {name} = {row[i]!r} is not a number") from None
    return out[0], out[1], out[2]


def _default_surrogate(data_dir: Path) -> Path:
    json_path = Path(data_dir) / "surrogate.json"
    return json_path if json_path.is_file() else Path(data_dir) / "surrogate.nc"


def to_csv(ds: xr.Dataset) -> str:
    """Prediction dataset as CSV text, one query per line, columns :data:`OUTPUT_COLUMNS`."""
    names = list(OUTPUT_COLUMNS)
    columns = [np.asarray(ds[n].values, dtype=float).ravel() for n in names]
    header = [f"{n}_{OUTPUT_COLUMNS[n][0]}" if OUTPUT_COLUMNS[n][0] != "1" else n for n in names]
    lines = [",".join(header)]
    lines += [",".join(f"{v:.10g}" for v in row) for row in zip(*columns)]
    return "\n".join(lines) + "\n"


def _chosen_surrogate(args: argparse.Namespace, scenario: Scenario) -> Any:
    """The surrogate that answers: ``--surrogate`` (either kind), else the run's own when it is of
    this surface, else the atlas's (``<data-dir>/atlas/surrogate.json``, else the one shipped in
    the package) when there is one."""
    from pipeline.predict_atlas import is_atlas_document, load_atlas_surrogate, shipped_path

    if args.surrogate is not None:
        path = Path(args.surrogate)
        if path.suffix == ".json" and path.is_file() and is_atlas_document(path.read_text()):
            return load_atlas_surrogate(path)
        return load_surrogate(path)
    own = _default_surrogate(args.data_dir)
    data_atlas = Path(args.data_dir) / "atlas" / "surrogate.json"
    atlas = data_atlas if data_atlas.is_file() else shipped_path()
    if own.is_file():
        tables = load_surrogate(own)
        try:
            check_surface(tables, scenario, extrapolate=False)
            return tables
        except ConfigError:
            if atlas is None:
                return tables  # predict refuses the surface, naming the run's own surrogate
    return load_atlas_surrogate(atlas) if atlas is not None else load_surrogate(own)


def predict_cli(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom predict``: CSV of R_el, its band and the band's components; warnings on stderr."""
    force, xi, lam = _cli_queries(args)
    _check_values(force, xi, lam)
    if args.roughness is not None:
        scenario = with_measured_roughness(scenario, args.roughness, args.pixel_size)
    elif args.pixel_size is not None:
        raise ConfigError("--pixel-size is only used with --roughness FILE")
    answer = _chosen_surrogate(args, scenario)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        if isinstance(answer, SurrogateTables):
            result = predict(answer, scenario, force, xi, lam, extrapolate=args.extrapolate,
                             model=args.model)
        else:
            from pipeline.predict_atlas import predict_atlas

            result = predict_atlas(answer, scenario, force, xi, lam, extrapolate=args.extrapolate)
    for w in caught:
        print(f"g2tom: warning: {w.message}", file=sys.stderr)
    print(f"g2tom: answered by {result.attrs['answered_by']}", file=sys.stderr)
    text = to_csv(result)
    if args.output is None:
        sys.stdout.write(text)
    else:
        from pipeline.store import atomic_path

        with atomic_path(args.output) as tmp:
            tmp.write_text(text)
