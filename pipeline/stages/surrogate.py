"""Stage 5: the truncated-SVD polynomial surrogate of alpha and gamma (Eq. 26).

Reads ``fits.nc``, writes ``surrogate.nc``, ``table3.csv`` and ``table3.md``.

``surrogate.nc`` holds, for ``p`` in (alpha, gamma):

* ``{p}_coef_w`` (mode, {p}_power_w) and ``{p}_coef_z`` (mode, {p}_power_z): ascending
  polynomial coefficients of the modes in w = log(lambda) and z = -log(1 - xi)
  (the project's Table 4); ``{p}(lambda, xi) = sum_k P_k(w) Q_k(z)``;
* ``{p}_mode_lambda`` / ``{p}_mode_xi``: the SVD modes on the grid, ``{p}_singular_values``;
* ``{p}_fit``, ``{p}_surrogate``, ``{p}_relative_error`` (lambda, xi) (Table 3);
* ``{p}_loo`` (order_w, order_z): leave-one-line-out RMS relative error for every order pair
  (NaN where one line fewer cannot determine the fit), with the verdict in its attributes;
* the clean fit (``alpha_clean``, ``gamma_clean`` and intervals) and the fitted ranges
  (``xi_range``, ``lambda_range``, ``force_normalized_range``, dim ``end``);
* the band used by the predictor: ``band_ratio_lower`` = R'_16 / R'_c and
  ``band_ratio_upper`` = R'_c / R'_84 (lambda, xi, step), with R'_c the fitted reduction, on
  the fitted load steps (coordinate ``force_normalized`` on ``step``), and
  ``open_probability`` on the same grid. Both ratios lie in [0, 1] for a sensible band; a
  zero upper ratio means more than 16 % open circuits (R_84 = inf). The predictor
  interpolates them linearly in (w, z, log F') and applies them to its R_el.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.compute import ComputeOptions
from pipeline.config import ConfigError, Scenario
from pipeline.physics.surrogate import fit_surrogate, order_scan
from pipeline.stages.fits import COORD_LABELS
from pipeline.store import atomic_path, read_stage, write_dataset

__all__ = ["build", "run", "table3_rows", "table3_csv", "table3_markdown", "PARAMETERS"]

PARAMETERS = ("alpha", "gamma")
#: Highest orders tried by the cross-validation scan.
MAX_ORDER_W = 4
MAX_ORDER_Z = 3


def _orders(scenario: Scenario, name: str) -> tuple[int, int]:
    s = scenario.surrogate
    return getattr(s, f"{name}_order_w"), getattr(s, f"{name}_order_z")


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


def _effective(scenario: Scenario, name: str, n_lam: int, n_xi: int) -> tuple[int, int, int]:
    """Rank and orders clipped to what the grid can determine, with a warning if clipped."""
    order_w, order_z = _orders(scenario, name)
    rank = min(scenario.surrogate.rank, n_lam, n_xi)
    eff = (rank, min(order_w, n_lam - 1), min(order_z, n_xi - 1))
    if eff != (scenario.surrogate.rank, order_w, order_z):
        warnings.warn(
            f"surrogate for {name}: rank/orders ({scenario.surrogate.rank}, w {order_w}, z {order_z}) "
            f"reduced to ({eff[0]}, w {eff[1]}, z {eff[2]}) for a {n_lam} x {n_xi} (lambda x xi) grid",
            stacklevel=3,
        )
    return eff


def _loo(name: str, matrix: np.ndarray, lam: np.ndarray, xi: np.ndarray, rank: int, order: tuple[int, int]) -> xr.DataArray:
    scan = order_scan(matrix, lam, xi, rank, MAX_ORDER_W, MAX_ORDER_Z)
    configured = scan[order] if order[0] <= MAX_ORDER_W and order[1] <= MAX_ORDER_Z else np.nan
    attrs = {"units": "1", "long_name": f"leave-one-line-out RMS relative error of {name}", "configured": configured}
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


def _parameter(scenario: Scenario, fits: xr.Dataset, name: str) -> dict[str, xr.DataArray]:
    matrix = _grid_matrix(fits, name)
    lam, xi = fits["lambda"].values, fits["xi"].values
    rank, order_w, order_z = _effective(scenario, name, lam.size, xi.size)
    model = fit_surrogate(matrix, lam, xi, rank, order_w, order_z)
    values = model(lam[:, None], xi[None, :])
    grid = ("lambda", "xi")
    return {
        f"{name}_coef_w": xr.DataArray(model.coef_w, dims=("mode", f"{name}_power_w"), attrs={"units": "1", "long_name": f"{name}: mode polynomials in w = log(lambda), ascending powers"}),
        f"{name}_coef_z": xr.DataArray(model.coef_z, dims=("mode", f"{name}_power_z"), attrs={"units": "1", "long_name": f"{name}: mode polynomials in z = -log(1 - xi), ascending powers"}),
        f"{name}_mode_lambda": xr.DataArray(model.modes_w, dims=("mode", "lambda"), attrs={"units": "1", "long_name": f"{name}: SVD modes u_k(lambda) = sqrt(s_k) U_k"}),
        f"{name}_mode_xi": xr.DataArray(model.modes_z, dims=("mode", "xi"), attrs={"units": "1", "long_name": f"{name}: SVD modes v_k(xi) = sqrt(s_k) V_k"}),
        f"{name}_singular_values": xr.DataArray(model.singular_values, dims=("component",), attrs={"units": "1", "long_name": f"{name}: all singular values of the grid matrix"}),
        f"{name}_fit": xr.DataArray(matrix, dims=grid, attrs={"units": "1", "long_name": f"fitted {name}"}),
        f"{name}_surrogate": xr.DataArray(values, dims=grid, attrs={"units": "1", "long_name": f"surrogate {name}"}),
        f"{name}_relative_error": xr.DataArray(values / matrix - 1.0, dims=grid, attrs={"units": "1", "long_name": f"surrogate / fitted {name} - 1"}),
        f"{name}_loo": _loo(name, matrix, lam, xi, rank, (order_w, order_z)),
    }


def _band(fits: xr.Dataset) -> dict[str, xr.DataArray]:
    """Band ratios and open probability on the fitted steps, dims (lambda, xi, step)."""
    steps = fits["fitted"].values.astype(bool)
    center = fits[f"{fits.attrs['reduction']}_normalized"]
    quant = fits["resistance_quantile_normalized"]
    with np.errstate(divide="ignore", invalid="ignore"):
        lower = quant.sel(quantile=0.16) / center
        upper = center / quant.sel(quantile=0.84)
    out = {}
    for name, value in {"band_ratio_lower": lower, "band_ratio_upper": upper, "open_probability": fits["open_probability"]}.items():
        value = value.isel(delta=steps).transpose("lambda", "xi", "delta")
        out[name] = xr.DataArray(value.values, dims=("lambda", "xi", "step"))
    out["band_ratio_lower"].attrs = {"units": "1", "long_name": "R'_16 / R'_center"}
    out["band_ratio_upper"].attrs = {"units": "1", "long_name": "R'_center / R'_84 (0: R_84 = inf)"}
    out["open_probability"].attrs = {"units": "1", "long_name": "share of open-circuit realizations"}
    return out


def build(scenario: Scenario, fits: xr.Dataset) -> xr.Dataset:
    """The surrogate dataset of a fits dataset (see the module docstring)."""
    ds = xr.Dataset(coords={"lambda": fits["lambda"].values, "xi": fits["xi"].values})
    for name in PARAMETERS:
        for key, value in _parameter(scenario, fits, name).items():
            ds[key] = value
    ds.update(_band(fits))
    steps = fits["fitted"].values.astype(bool)
    force_n = fits["force_normalized"].values[steps]
    ds = ds.assign_coords(force_normalized=("step", force_n), force=("step", fits["force"].values[steps]))
    ds["force_normalized"].attrs = {"units": "1", "long_name": "F' = 2F/(E* sqrt(R* sigma^3))"}
    ds["force"].attrs = {"units": "N", "long_name": "normal force"}
    end = {"end": ["min", "max"]}
    ranges = {"xi": ds.xi.values, "lambda": ds["lambda"].values, "force_normalized": force_n}
    for name, values in ranges.items():
        ds[f"{name}_range"] = xr.DataArray(
            [values.min(), values.max()], dims="end", coords=end, attrs={"units": "1", "long_name": f"fitted range of {name}"}
        )
    for name in ("xi", "lambda"):
        ds[name].attrs = {"units": COORD_LABELS[name][0], "long_name": COORD_LABELS[name][1]}
    ds["order_w"].attrs = {"units": "1", "long_name": "polynomial order in w tried by cross-validation"}
    ds["order_z"].attrs = {"units": "1", "long_name": "polynomial order in z tried by cross-validation"}
    for key in ("alpha_clean", "gamma_clean", "alpha_clean_ci", "gamma_clean_ci"):
        ds[key] = fits[key]
    ds.attrs["reduction"] = fits.attrs["reduction"]
    ds.attrs["model"] = "p(lambda, xi) = sum_k P_k(log lambda) Q_k(-log(1 - xi)) (Eq. 26)"
    ds.attrs["predictor"] = "R_el = alpha 2 rho*/sqrt(R* sigma) F'^-gamma (Eq. 27)"
    return ds


def table3_rows(ds: xr.Dataset) -> list[dict[str, float]]:
    """One row per (xi, lambda): fitted value, surrogate value and relative error (%)."""
    rows = []
    for xi in ds["xi"].values:
        for lam in ds["lambda"].values:
            row: dict[str, float] = {"xi": float(xi), "lambda": float(lam)}
            for p in PARAMETERS:
                cell = {"lambda": lam, "xi": xi}
                row[f"{p}_fit"] = float(ds[f"{p}_fit"].sel(cell))
                row[f"{p}_surrogate"] = float(ds[f"{p}_surrogate"].sel(cell))
                row[f"{p}_error_percent"] = 100.0 * float(ds[f"{p}_relative_error"].sel(cell))
            rows.append(row)
    return rows


def table3_csv(ds: xr.Dataset) -> str:
    """Table 3 as CSV text (header line first)."""
    rows = table3_rows(ds)
    lines = [",".join(rows[0])]
    lines += [",".join(f"{v:.6g}" for v in row.values()) for row in rows]
    return "\n".join(lines) + "\n"


def table3_markdown(ds: xr.Dataset) -> str:
    """Table 3 as a Markdown table."""
    header = ["xi", "lambda", "alpha fit", "alpha SVD", "err %", "gamma fit", "gamma SVD", "err %"]
    lines = ["| " + " | ".join(header) + " |", "|" + "---:|" * len(header)]
    for row in table3_rows(ds):
        cells = [f"{row['xi']:g}", f"{row['lambda']:g}"]
        for p in PARAMETERS:
            cells += [f"{row[f'{p}_fit']:.4f}", f"{row[f'{p}_surrogate']:.4f}", f"{row[f'{p}_error_percent']:+.2f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Read ``fits.nc``; write ``surrogate.nc``, ``table3.csv`` and ``table3.md``.

    ``options`` is accepted for the stage interface; the work is small numpy linear algebra.
    """
    fits = read_stage(data_dir, "fits", scenario)
    ds = build(scenario, fits)
    path = write_dataset(ds, data_dir, "surrogate", scenario)
    for name, text in (("table3.csv", table3_csv(ds)), ("table3.md", table3_markdown(ds))):
        with atomic_path(Path(data_dir) / name) as tmp:
            tmp.write_text(text)
    return path
