"""Stage 5: the surrogate of alpha and gamma (Eq. 26) and the predictor's tables.

Reads ``fits.nc``; writes ``surrogate.nc``, ``surrogate.json`` (everything the predictor
needs, see :mod:`g2tom.stages.surrogate_file`), ``table3.csv`` and ``table3.md``.

Two methods (``surrogate.method``):

* ``paper``: the paper's Sect. 3.1: truncated SVD of the grid matrix, each mode fitted by its
  own polynomial, with the configured rank and orders;
* ``joint``: ``T(p) = sum_k P_k(w) Q_k(z)`` with T = log or identity and w = log(lambda),
  lambda or sqrt(lambda) (``surrogate.lambda_map``; the spec string ``T`` or ``T;w=<map>``), all coefficients fitted
  at once by weighted least squares (weights 1 / max(relative 95 % half-width,
  ``weight_floor``)^2 from ``fits.nc``'s ``{p}_ci``), transform, rank and orders chosen by
  leave-one-line-out cross-validation (:func:`g2tom.fitting.surrogate_joint.select_model`).

A grid with fewer than three values of oxide.xi or oxide.lambda (one cell, one row) is too small
for ``joint``: the stage then fits ``paper`` with the most rank and orders the grid determines,
through every cell (one cell: a constant, that cell's alpha and gamma), records why in the
attribute ``trivial`` and the method fitted in ``method``
(:func:`g2tom.before_work.surrogate_grid.small_grid_note`).

``surrogate.nc`` holds, for ``p`` in (alpha, gamma):

* ``{p}_coef_w`` ({p}_mode, {p}_power_w) and ``{p}_coef_z`` ({p}_mode, {p}_power_z): ascending
  coefficients of the modes in w = log(lambda) and z = -log(1 - xi);
  ``T(p)(lambda, xi) = sum_k P_k(w) Q_k(z)``, T named in their ``transform`` attribute;
* ``{p}_fit``, ``{p}_surrogate``, ``{p}_relative_error`` (lambda, xi) (Table 3);
* ``{p}_cv_error`` (lambda, xi): RMS over the two left-out predictions of each cell (its row
  left out, its column left out) of ln(prediction / fit) for alpha and of
  (prediction - fit) for gamma (NaN where the grid is too small to cross-validate);
* ``{p}_fit_sigma`` (lambda, xi): the fit's confidence interval as one standard deviation of
  ln alpha, or of gamma: (upper - lower) / (2 z_c), z_c the normal quantile of the level;
* the model in the attributes ``{p}_transform``, ``{p}_rank``, ``{p}_order_w``,
  ``{p}_order_z``, ``{p}_free_parameters`` (r (p + q - r)), ``{p}_cv_rms`` and
  ``{p}_formula`` (a closed formula);
* paper method: ``{p}_mode_lambda`` / ``{p}_mode_xi`` (SVD modes), ``{p}_singular_values``,
  ``{p}_loo`` (order_w, order_z): leave-one-line-out RMS relative error for every order pair;
  joint method: ``{p}_cv_rms`` ({p}_candidate) with the candidates' ``{p}_cv_transform``,
  ``{p}_cv_rank``, ``{p}_cv_order_w``, ``{p}_cv_order_z``, ``{p}_cv_free_parameters``;
* the clean fit (``alpha_clean``, ``gamma_clean`` and intervals) and the fitted ranges
  (``xi_range``, ``lambda_range``, ``force_normalized_range``, dim ``end``);
* the scene's dimensionless groups in the attributes ``mu`` and ``Pi`` (and ``indenter_shape``):
  the surrogate is of that surface only, and the predictor refuses others;
* the realization band: ``band_ratio_lower`` = R'_16 / R'_c and ``band_ratio_upper`` =
  R'_c / R'_84 (lambda, xi, step), R'_c the fitted reduction, on the fitted load steps
  (coordinate ``force_normalized`` on ``step``), and ``open_probability`` on the same grid;
  a zero upper ratio means more than 16 % open circuits (R_84 = inf).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr
from scipy.special import ndtri

from g2tom.before_work.surrogate_grid import small_grid_note
from g2tom.compute import ComputeOptions, single_threaded
from g2tom.config import ConfigError, Scenario
from g2tom.fitting import surrogate as sg
from g2tom.fitting import surrogate_joint as sg_joint
from g2tom.fitting import surrogate_paper as sg_paper
from g2tom.stages.schema import SURROGATE_COORDINATES, array
from g2tom.stages.schema import attrs as schema_attrs
from g2tom.stages.surrogate_file import SurrogateTables
from g2tom.stages.surrogate_tables import band_tables, curve_tables
from g2tom.stages.table3 import PARAMETERS, table3_csv, table3_markdown
from g2tom.store import atomic_path, read_stage, write_dataset
from g2tom.scene import scene_groups

__all__ = ["build", "run", "PARAMETERS"]

#: Highest orders tried by the paper method's cross-validation scan.
MAX_ORDER_W = 4
MAX_ORDER_Z = 3
GRID = ("lambda", "xi")


def _grid_matrix(fits: xr.Dataset, name: str) -> np.ndarray:
    """(lambda, xi) matrix of a fitted parameter; ConfigError if any cell is missing."""
    field = fits[name].transpose("lambda", "xi")
    bad = ~np.isfinite(field)
    if bool(bad.any()):
        where = field.where(bad, drop=True)
        raise ConfigError(
            f"{name} could not be fitted at xi = {where['xi'].values.tolist()}, lambda = "
            f"{where['lambda'].values.tolist()} (no conducting realization on >= 2 fitted steps): "
            f"lower fits.min_force or drop those oxide.xi / oxide.lambda values"
        )
    return field.values


def _half_width(fits: xr.Dataset, name: str) -> np.ndarray:
    """Half-width of the fit's confidence interval per cell (lambda, xi), in units of the parameter."""
    ci = fits[f"{name}_ci"].transpose("lambda", "xi", "bound")
    return (ci.sel(bound="upper").values - ci.sel(bound="lower").values) / 2.0


def _fit_sigma(scenario: Scenario, fits: xr.Dataset, name: str) -> np.ndarray:
    """One standard deviation of ln alpha (name alpha) or of gamma from the fit's interval."""
    z_c = ndtri(0.5 + scenario.fits.confidence / 2.0)
    ci = fits[f"{name}_ci"].transpose("lambda", "xi", "bound")
    lower, upper = ci.sel(bound="lower").values, ci.sel(bound="upper").values
    if name == "alpha":
        with np.errstate(divide="ignore", invalid="ignore"):
            return (np.log(upper) - np.log(lower)) / (2.0 * z_c)
    return (upper - lower) / (2.0 * z_c)


def _cv_error(name: str, predictions: np.ndarray | None, matrix: np.ndarray) -> np.ndarray:
    """Per-cell RMS of the left-out errors: of ln(pred/fit) for alpha, of pred - fit for gamma."""
    if predictions is None:
        return np.full(matrix.shape, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        diff = np.log(predictions / matrix) if name == "alpha" else predictions - matrix
    return np.sqrt(np.mean(diff**2, axis=0))


def _reduced(name: str, what: str, wanted: tuple[int, ...], limits: tuple[int, ...], shape: tuple[int, int]) -> tuple[int, ...]:
    """Rank and orders clipped to what the grid can determine, with a warning if clipped."""
    eff = tuple(min(a, b) for a, b in zip(wanted, limits))
    if eff != wanted:
        warnings.warn(
            f"surrogate for {name}: rank/orders {what}({wanted[0]}, w {wanted[1]}, z {wanted[2]}) "
            f"reduced to ({eff[0]}, w {eff[1]}, z {eff[2]}) for a {shape[0]} x {shape[1]} (lambda x xi) grid",
            stacklevel=5,
        )
    return eff


def _loo(name: str, matrix: np.ndarray, lam: np.ndarray, xi: np.ndarray, rank: int, order: tuple[int, int]) -> xr.DataArray:
    scan = sg_paper.order_scan(matrix, lam, xi, rank, MAX_ORDER_W, MAX_ORDER_Z)
    configured = scan[order] if order[0] <= MAX_ORDER_W and order[1] <= MAX_ORDER_Z else np.nan
    attrs = {**schema_attrs("surrogate", f"{name}_loo"), "configured": configured}
    if np.all(np.isnan(scan)):
        attrs["verdict"] = "grid too small for leave-one-out cross-validation"
    else:
        best = np.unravel_index(np.nanargmin(scan), scan.shape)
        attrs.update(best=scan[best], best_order_w=int(best[0]), best_order_z=int(best[1]))
        if not np.isfinite(configured):
            attrs["verdict"] = (
                f"the configured orders (w {order[0]}, z {order[1]}) cannot be cross-validated on this grid "
                f"(outside the scan, or one line fewer does not determine them); the best scanned orders are "
                f"(w {best[0]}, z {best[1]}) ({scan[best]:.3g})"
            )
        elif scan[best] < configured:
            attrs["verdict"] = f"orders (w {best[0]}, z {best[1]}) generalize better ({scan[best]:.3g} vs {configured:.3g})"
        else:
            attrs["verdict"] = f"the configured orders (w {order[0]}, z {order[1]}) generalize best ({configured:.3g})"
    return xr.DataArray(
        scan, dims=("order_w", "order_z"),
        coords={"order_w": np.arange(MAX_ORDER_W + 1), "order_z": np.arange(MAX_ORDER_Z + 1)}, attrs=attrs,
    )


def _paper(scenario: Scenario, name: str, matrix: np.ndarray, lam: np.ndarray, xi: np.ndarray) -> tuple[dict, dict]:
    """The paper's method: variables, model attributes and the left-out predictions.

    Configured (``surrogate.method = 'paper'``), orders reduced to the grid are warned about; as the
    trivial fit of a grid too small for the joint method (:func:`small_grid_note`, said once
    before the run) rank and orders are the most the grid determines, so that the fit passes
    through every cell.
    """
    s = scenario.surrogate
    limits = (min(lam.size, xi.size), lam.size - 1, xi.size - 1)
    if s.method != "paper":
        rank, order_w, order_z = limits
    else:
        wanted = (s.rank, getattr(s, f"{name}_order_w"), getattr(s, f"{name}_order_z"))
        rank, order_w, order_z = _reduced(name, "", wanted, limits, (lam.size, xi.size))
    model = sg_paper.fit_surrogate(matrix, lam, xi, rank, order_w, order_z)
    predictions = sg_paper.paper_loo_predictions(matrix, lam, xi, rank, order_w, order_z)
    loo = _loo(name, matrix, lam, xi, rank, (order_w, order_z))
    variables = {
        f"{name}_mode_lambda": array("surrogate", f"{name}_mode_lambda", model.modes_w),
        f"{name}_mode_xi": array("surrogate", f"{name}_mode_xi", model.modes_z),
        f"{name}_singular_values": array("surrogate", f"{name}_singular_values", model.singular_values),
        f"{name}_loo": loo,
    }
    cv_rms = float(np.sqrt(np.mean((predictions / matrix - 1.0) ** 2))) if predictions is not None else float("nan")
    info = {"transform": "identity", "rank": rank, "order_w": order_w, "order_z": order_z, "cv_rms": cv_rms,
            "coef_w": model.coef_w, "coef_z": model.coef_z, "predictions": predictions}
    return variables, info


def _joint(scenario: Scenario, fits: xr.Dataset, name: str, matrix: np.ndarray, lam: np.ndarray, xi: np.ndarray) -> tuple[dict, dict]:
    """The joint weighted fit with cross-validated transform, rank and orders."""
    s = scenario.surrogate
    wanted = (s.max_rank, s.max_order_w, s.max_order_z)
    limits = (min(lam.size, xi.size) - 1, lam.size - 2, xi.size - 2)  # one line fewer must determine them
    max_rank, max_w, max_z = _reduced(name, "scanned up to ", wanted, limits, (lam.size, xi.size))
    choice = getattr(s, f"{name}_transform")
    transforms = sg.TRANSFORMS if choice == "auto" else (choice,)
    if np.any(matrix <= 0) and "log" in transforms:
        if choice == "log":
            raise ConfigError(f"surrogate.{name}_transform = 'log' needs {name} > 0 on every cell (min {matrix.min():.4g})")
        transforms = ("identity",)
    w_maps = sg.W_MAPS if s.lambda_map == "auto" else (s.lambda_map,)
    specs = tuple(sg.model_spec(t, m) for m in w_maps for t in transforms)
    relative = np.fmax(np.abs(_half_width(fits, name) / matrix), s.weight_floor)
    sigma_of = {"log": relative, "identity": relative * np.abs(matrix)}
    best, tried = sg_joint.select_model(matrix, lam, xi, specs, max_rank, max_w, max_z, sigma_of, s.cv_tolerance)
    model = sg_joint.fit_joint(matrix, lam, xi, best.rank, best.order_w, best.order_z, best.transform, sigma_of[sg.split_spec(best.transform)[0]])
    variables = {f"{name}_cv_rms": array("surrogate", f"{name}_cv_rms", [c.score for c in tried])}
    for key in ("transform", "rank", "order_w", "order_z", "free_parameters"):
        variables[f"{name}_cv_{key}"] = array("surrogate", f"{name}_cv_{key}", [getattr(c, key) for c in tried])
    info = {"transform": best.transform, "rank": model.rank, "order_w": best.order_w, "order_z": best.order_z,
            "cv_rms": best.score, "coef_w": model.coef_w, "coef_z": model.coef_z, "predictions": best.predictions}
    return variables, info


def _parameter(scenario: Scenario, fits: xr.Dataset, name: str) -> tuple[dict[str, xr.DataArray], dict[str, object]]:
    matrix = _grid_matrix(fits, name)
    lam, xi = fits["lambda"].values, fits["xi"].values
    if _method(scenario) == "paper":
        variables, info = _paper(scenario, name, matrix, lam, xi)
    else:
        variables, info = _joint(scenario, fits, name, matrix, lam, xi)
    transform = str(info["transform"])
    values = sg.evaluate(info["coef_w"], info["coef_z"], lam[:, None], xi[None, :], transform)
    transformed = {"transformed": "log " + name if transform == "log" else name}
    variables.update({
        f"{name}_coef_w": array("surrogate", f"{name}_coef_w", info["coef_w"], transformed, transform=transform),
        f"{name}_coef_z": array("surrogate", f"{name}_coef_z", info["coef_z"], transformed, transform=transform),
        f"{name}_fit": array("surrogate", f"{name}_fit", matrix),
        f"{name}_surrogate": array("surrogate", f"{name}_surrogate", values),
        f"{name}_relative_error": array("surrogate", f"{name}_relative_error", values / matrix - 1.0),
        f"{name}_cv_error": array("surrogate", f"{name}_cv_error", _cv_error(name, info["predictions"], matrix)),
        f"{name}_fit_sigma": array("surrogate", f"{name}_fit_sigma", _fit_sigma(scenario, fits, name)),
    })
    attrs = {
        f"{name}_transform": transform,
        f"{name}_rank": int(info["rank"]),
        f"{name}_order_w": int(info["order_w"]),
        f"{name}_order_z": int(info["order_z"]),
        f"{name}_free_parameters": sg_joint.free_parameters(int(info["rank"]), int(info["order_w"]), int(info["order_z"])),
        f"{name}_cv_rms": float(info["cv_rms"]),
        f"{name}_formula": sg.closed_formula(info["coef_w"], info["coef_z"], transform, name),
    }
    return variables, attrs


def _method(scenario: Scenario) -> str:
    """The method fitted: the configured one, or ``paper`` on a grid too small for ``joint``."""
    return "paper" if small_grid_note(scenario) else scenario.surrogate.method


@single_threaded
def build(scenario: Scenario, fits: xr.Dataset) -> xr.Dataset:
    """The surrogate dataset of a fits dataset (see the module docstring)."""
    ds = xr.Dataset(coords={"lambda": fits["lambda"].values, "xi": fits["xi"].values})
    for name in PARAMETERS:
        variables, attrs = _parameter(scenario, fits, name)
        for key, value in variables.items():
            ds[key] = value
        ds.attrs.update(attrs)
    ds.update(band_tables(fits))
    ds.update(curve_tables(scenario, fits))
    steps = fits["fitted"].values.astype(bool)
    force_n = fits["force_normalized"].values[steps]
    ds = ds.assign_coords(force_normalized=("step", force_n), force=("step", fits["force"].values[steps]))
    ds["force_normalized"].attrs = schema_attrs("surrogate", "force_normalized")
    ds["force"].attrs = schema_attrs("surrogate", "force")
    end = {"end": ["min", "max"]}
    ranges = {"xi": ds.xi.values, "lambda": ds["lambda"].values, "force_normalized": force_n}
    for name, values in ranges.items():
        ds[f"{name}_range"] = xr.DataArray(
            [values.min(), values.max()], dims="end", coords=end, attrs=schema_attrs("surrogate", f"{name}_range")
        )
    for name in ("xi", "lambda"):
        ds[name].attrs = SURROGATE_COORDINATES[name].attrs()
    for name in ("order_w", "order_z"):
        if name in ds.coords:
            ds[name].attrs = schema_attrs("surrogate", name)
    for key in ("alpha_clean", "gamma_clean", "alpha_clean_ci", "gamma_clean_ci"):
        ds[key] = fits[key]
    ds.attrs["reduction"] = fits.attrs["reduction"]
    ds.attrs["method"] = _method(scenario)
    note = small_grid_note(scenario)
    if note:
        ds.attrs["trivial"] = note
    # the scene's dimensionless groups: the predictor answers only surfaces with these (g2tom.physics.groups)
    scene = scene_groups(scenario)
    ds.attrs["mu"], ds.attrs["Pi"] = scene.mu, scene.Pi
    ds.attrs["indenter_shape"] = scenario.indenter.shape
    if scenario.material.hardness is not None:  # capped caps: the predictor answers only this hardness
        ds.attrs["hardness"] = scenario.material.hardness
    ds.attrs["fit_confidence"] = scenario.fits.confidence
    ds.attrs["model"] = "T(p)(lambda, xi) = sum_k P_k(log lambda) Q_k(-log(1 - xi)), T = log or identity (Eq. 26)"
    ds.attrs["predictor"] = ("R_el = 2 rho*/sqrt(R* sigma) exp(sum_k c_k(xi, lambda) (ln F')^k), the curve model "
                             "interpolated linearly in (ln lambda, -ln(1 - xi)) (default); or alpha 2 rho*/sqrt(R* sigma) "
                             "F'^-gamma (Eq. 27, model = power_law)")
    return ds


@single_threaded
def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Read ``fits.nc``; write ``surrogate.nc``, ``surrogate.json``, ``table3.csv`` and ``table3.md``.

    ``options`` is accepted for the stage interface; the work is small numpy linear algebra.
    """

    fits = read_stage(data_dir, "fits", scenario)
    ds = build(scenario, fits)
    path = write_dataset(ds, data_dir, "surrogate", scenario)
    texts = {
        "surrogate.json": SurrogateTables.from_dataset(read_stage(data_dir, "surrogate", scenario)).to_json(),
        "table3.csv": table3_csv(ds),
        "table3.md": table3_markdown(ds),
    }
    for name, text in texts.items():
        with atomic_path(Path(data_dir) / name) as tmp:
            tmp.write_text(text)
    return path
