"""The phenomenological predictor of Eq. 27 from a fitted surrogate.

    R_el = alpha(xi, lambda) 2 rho* / sqrt(R* sigma) F'^-gamma(xi, lambda),
    F' = 2 F / (E* sqrt(R* sigma^3)),

with alpha and gamma evaluated from the polynomial modes stored in ``surrogate.nc``.
Material (E*, rho*), roughness (sigma) and indenter (R*) come from the scenario. The
16–84 % band applies the band ratios stored in ``surrogate.nc`` (see
:mod:`pipeline.stages.surrogate`), interpolated linearly in (log lambda, -log(1 - xi),
log F') and clamped to the fitted grid. Outside the fitted ranges of xi, lambda or F' the
prediction is an extrapolation and a :class:`ExtrapolationWarning` says so.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr
from scipy.interpolate import RegularGridInterpolator

from pipeline.config import ConfigError, Scenario
from pipeline.physics.surrogate import evaluate, to_w, to_z

__all__ = ["ExtrapolationWarning", "Prediction", "load_surrogate", "predict", "predict_cli"]


class ExtrapolationWarning(UserWarning):
    """xi, lambda or F' lies outside the range the surrogate was fitted on."""


@dataclass(frozen=True)
class Prediction:
    """A prediction of Eq. 27.

    Attributes
    ----------
    resistance
        R_el, ohm.
    lower, upper
        16 % and 84 % band of R_el, ohm (NaN: unavailable; +inf: > 16 % open circuits).
    alpha, gamma
        Surrogate values at (xi, lambda), dimensionless.
    force_normalized
        F', dimensionless.
    open_probability
        Interpolated share of open circuits, dimensionless.
    """

    resistance: float
    lower: float
    upper: float
    alpha: float
    gamma: float
    force_normalized: float
    open_probability: float


def load_surrogate(path: str | Path) -> xr.Dataset:
    """Load ``surrogate.nc`` into memory.

    Raises
    ------
    ConfigError
        If the file is missing or is not a surrogate file.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"--surrogate {str(path)!r} does not exist: run `g2tom surrogate` (or `make surrogate`) first")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise ConfigError(f"--surrogate {str(path)!r} is not a readable netCDF file ({exc})") from None
    if "alpha_coef_w" not in ds or "gamma_coef_w" not in ds:
        raise ConfigError(f"--surrogate {str(path)!r} holds no surrogate coefficients (alpha_coef_w, gamma_coef_w)")
    return ds


def _check_inputs(force: float, xi: float, lam: float) -> None:
    if not (math.isfinite(force) and force > 0):
        raise ConfigError(f"--force = {force!r} is out of range: must be > 0 (N)")
    if not (math.isfinite(xi) and 0 < xi < 1):
        raise ConfigError(f"--xi = {xi!r} is out of range: must be in (0, 1)")
    if not (math.isfinite(lam) and lam > 0):
        raise ConfigError(f"--lambda = {lam!r} is out of range: must be > 0")


def _warn_outside(name: str, value: float, limits: np.ndarray) -> None:
    lo, hi = float(limits[0]), float(limits[1])
    if not lo <= value <= hi:
        warnings.warn(
            f"{name} = {value:.4g} lies outside the fitted range [{lo:.4g}, {hi:.4g}]: the prediction is an extrapolation",
            ExtrapolationWarning,
            stacklevel=3,
        )


def _band_point(surrogate: xr.Dataset, name: str, xi: float, lam: float, force_n: float) -> float:
    """Linear interpolation of a (lambda, xi, step) field in (w, z, log F'), clamped to the grid."""
    axes = (to_w(surrogate["lambda"].values), to_z(surrogate["xi"].values), np.log(surrogate["force_normalized"].values))
    point = [float(np.clip(v, a.min(), a.max())) for v, a in zip((to_w(lam), to_z(xi), math.log(force_n)), axes)]
    values = surrogate[name].transpose("lambda", "xi", "step").values
    singleton = [a.size == 1 for a in axes]
    axes = tuple(a for a, s in zip(axes, singleton) if not s)
    point = [p for p, s in zip(point, singleton) if not s]
    values = values[tuple(0 if s else slice(None) for s in singleton)]
    if not axes:
        return float(values)
    return float(RegularGridInterpolator(axes, values)(point)[0])


def predict(surrogate: xr.Dataset, scenario: Scenario, force: float, xi: float, lam: float) -> Prediction:
    """R_el of Eq. 27 and its 16–84 % band.

    Parameters
    ----------
    surrogate
        A dataset from :func:`load_surrogate` (or the surrogate stage).
    scenario
        Supplies material (E*, rho*), roughness (sigma) and indenter (R*).
    force
        Normal force F, N, > 0.
    xi
        Oxide fraction, in (0, 1).
    lam
        Normalized oxide correlation length l_O sqrt(eta), > 0.

    Raises
    ------
    ConfigError
        If an input is out of range.

    Warns
    -----
    ExtrapolationWarning
        If xi, lambda or F' lies outside the fitted ranges.
    """
    _check_inputs(force, xi, lam)
    force_n = force / scenario.force_scale
    _warn_outside("xi", xi, surrogate["xi_range"].values)
    _warn_outside("lambda", lam, surrogate["lambda_range"].values)
    _warn_outside("F'", force_n, surrogate["force_normalized_range"].values)
    alpha = float(evaluate(surrogate["alpha_coef_w"].values, surrogate["alpha_coef_z"].values, lam, xi))
    gamma = float(evaluate(surrogate["gamma_coef_w"].values, surrogate["gamma_coef_z"].values, lam, xi))
    if not alpha > 0:
        raise ConfigError(
            f"the surrogate gives alpha = {alpha:.4g} <= 0 at xi = {xi:g}, lambda = {lam:g}: "
            "too far outside the fitted range"
        )
    resistance = alpha * scenario.resistance_scale * force_n**-gamma
    ratio_lower = _band_point(surrogate, "band_ratio_lower", xi, lam, force_n)
    ratio_upper = _band_point(surrogate, "band_ratio_upper", xi, lam, force_n)
    upper = math.inf if ratio_upper == 0 else resistance / ratio_upper  # 0: > 16 % open circuits
    return Prediction(
        resistance=resistance,
        lower=resistance * ratio_lower,
        upper=upper,
        alpha=alpha,
        gamma=gamma,
        force_normalized=force_n,
        open_probability=_band_point(surrogate, "open_probability", xi, lam, force_n),
    )


def predict_cli(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom predict``: print R_el and its band; extrapolation warnings go to stderr."""
    _check_inputs(args.force, args.xi, args.lam)
    path = args.surrogate if args.surrogate is not None else Path(args.data_dir) / "surrogate.nc"
    surrogate = load_surrogate(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExtrapolationWarning)
        result = predict(surrogate, scenario, args.force, args.xi, args.lam)
    for w in caught:
        print(f"g2tom: warning: {w.message}", file=sys.stderr)
    print(f"R_el = {result.resistance:.6g} ohm  (16-84 %: {result.lower:.6g} .. {result.upper:.6g} ohm)")
    print(
        f"alpha = {result.alpha:.6g}, gamma = {result.gamma:.6g}, F' = {result.force_normalized:.6g}, "
        f"open-circuit probability ~ {result.open_probability:.3g}"
    )
    print(
        f"material/roughness: rho* = {scenario.material.rho:g} ohm m, E* = {scenario.material.E_star:.6g} Pa, "
        f"sigma = {scenario.roughness.sigma:g} m, R* = {scenario.indenter.radius:g} m"
    )
