"""Report sections on the results: the clean-surface fit, the ensemble, the surrogate and its tables."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import ndtri

from g2tom.analysis.report_blocks import Block, table as _table
from g2tom.config import Scenario
from g2tom.fitting import surrogate as sg
from g2tom.stages.table3 import PARAMETERS, table3_rows

__all__ = ["fit_blocks", "ensemble_blocks", "surrogate_model_blocks", "surrogate_table_blocks", "surrogate_half_width",
           "surrogate_misses"]


def fit_blocks(fits: xr.Dataset, scenario: Scenario) -> list[Block]:
    f = scenario.fits
    ci = {k: fits[f"{k}_clean_ci"].values for k in ("alpha", "gamma")}
    steps = int(fits["fitted"].sum())
    return [
        Block("h2", "Clean-surface fit"),
        Block("p", f"R' = alpha F'^-gamma fitted by least squares in log-log on the {steps} load steps with "
                   f"{fits.attrs.get('fit_range', f'F >= {f.min_force:g} N')}; intervals: "
                   f"{100 * f.confidence:g} % least-squares (Student t)."),
        _table(["parameter", "value", "lower", "upper"], [
            ["alpha_clean", float(fits["alpha_clean"]), float(ci["alpha"][0]), float(ci["alpha"][1])],
            ["gamma_clean", float(fits["gamma_clean"]), float(ci["gamma"][0]), float(ci["gamma"][1])],
            ["RMS log residual", float(fits["fit_residual_rms_clean"]), "", ""],
        ]),
        Block("p", f"Oxidized cells: reduction '{f.reduction}' over realizations (geometric and arithmetic "
                   f"means over conducting realizations only); {100 * f.confidence:g} % percentile intervals of "
                   f"alpha and gamma (fits.nc: alpha_ci, gamma_ci) from {f.n_bootstrap} bootstrap resamples over "
                   f"realizations (seed {f.seed}); largest open-circuit probability on the fitted steps "
                   f"{float(fits['open_probability'].isel(delta=fits['fitted'].values.astype(bool)).max()):.3g}."),
    ]


def surrogate_half_width(sur: xr.Dataset, parameter: str, z: float) -> np.ndarray:
    """Relative confidence half-width (lambda, xi) of the fitted ``alpha`` or ``gamma`` of each cell
    (``z`` standard errors of the fit)."""
    sigma = sur[f"{parameter}_fit_sigma"].values * z
    return np.expm1(sigma) if parameter == "alpha" else sigma / sur[f"{parameter}_fit"].values


def surrogate_misses(sur: xr.Dataset, parameter: str, z: float) -> list[str]:
    """The cells where the surrogate of ``parameter`` misses max(3 %, the cell's half-width), as text."""
    err = np.abs(sur[f"{parameter}_relative_error"])
    bound = np.fmax(0.03, surrogate_half_width(sur, parameter, z))
    out = []
    for i, j in zip(*np.nonzero(err.values > bound)):
        out.append(f"{parameter} at xi {float(sur['xi'][j]):g}, lambda {float(sur['lambda'][i]):g}: "
                   f"{100 * float(err.values[i, j]):.2f} % against {100 * float(bound[i, j]):.2f} %")
    return out


def surrogate_model_blocks(sur: xr.Dataset) -> list[Block]:
    """Method, model sizes, errors and the closed formulas of the surrogate."""
    z_c = float(ndtri(0.5 + float(sur.attrs.get("fit_confidence", 0.95)) / 2.0))
    method = sur.attrs.get("method", "paper")
    rows, misses = [], []
    for p in PARAMETERS:
        a = sur.attrs
        err = np.abs(sur[f"{p}_relative_error"].values)
        half = surrogate_half_width(sur, p, z_c)
        met = int(np.sum(err <= np.fmax(0.03, half)))
        misses += surrogate_misses(sur, p, z_c)
        transform, w_map = sg.split_spec(str(a.get(f"{p}_transform", "identity")))
        rows.append([p, transform, sg.W_TEXT[w_map], int(a.get(f"{p}_rank", 0)), int(a.get(f"{p}_order_w", 0)),
                     int(a.get(f"{p}_order_z", 0)), int(a.get(f"{p}_free_parameters", 0)), f"{100 * float(a.get(f'{p}_cv_rms', np.nan)):.2f}",
                     f"{100 * err.max():.2f}", f"{100 * np.sqrt(np.mean(err**2)):.2f}", f"{met} / {err.size}"])
    text = ("joint weighted least-squares fit of all coefficients of the rank-r model T(p) = sum_k P_k(w) Q_k(z), "
            "each cell weighted by its confidence interval; transform, coordinate w of lambda, rank and orders chosen "
            "by leave-one-line-out "
            "cross-validation" if method == "joint" else
            "the paper's Sect. 3.1: truncated SVD of the grid matrix, each mode fitted by its own polynomial")
    formulas = "\n".join(str(sur.attrs.get(f"{p}_formula", "")) for p in PARAMETERS)
    return [
        Block("h2", "Surrogate (Eq. 26)"),
        *([Block("p", f"Trivial: {sur.attrs['trivial']}.")] if "trivial" in sur.attrs else []),
        Block("p", f"Method '{method}': {text}. Free parameters of a rank-r product of polynomial spaces of "
                   f"dimensions p and q: r (p + q - r). CV: RMS relative error of each grid value predicted with its "
                   f"lambda row or xi column left out. Target per cell: |error| <= max(3 %, the cell's "
                   f"{100 * float(sur.attrs.get('fit_confidence', 0.95)):g} % half-width)."),
        _table(["parameter", "transform T", "w", "rank r", "order w", "order z", "free parameters", "CV RMS %",
                "max |error| %", "RMS error %", "cells within target"], rows),
        Block("p", "Cells outside the target (flagged; the predictor's band carries the local cross-validated error "
                   "there): " + "; ".join(misses) + "." if misses else "Every cell is within the target."),
        Block("p", "Closed formulas (w = LN(lambda) where written in w, z = -LN(1 - xi); also in surrogate.json with everything the "
                   "predictor needs):"),
        Block("pre", formulas),
        Block("p", "Predictor bands (g2tom predict), each from one-sigma half-widths in ln R: the 95 % interval of "
                   "the predicted mean, R exp(-/+ 1.96 sqrt(f^2 + e^2)) (resistance_mean_lower, resistance_mean_upper) "
                   "with the fit's interval f = sqrt(s_a^2 + (ln F' s_g)^2) from alpha_ci, gamma_ci and the "
                   "surrogate's local cross-validated error e = sqrt(e_a^2 + (ln F' e_g)^2); and the spread over "
                   "contacts, 16-84 % of R over realizations (resistance_spread_p16, resistance_spread_p84). "
                   f"Local cross-validated error of ln alpha: median {100 * float(np.nanmedian(sur['alpha_cv_error'])):.2f} %, "
                   f"largest {100 * float(np.nanmax(sur['alpha_cv_error'])):.2f} %; of gamma: median "
                   f"{float(np.nanmedian(sur['gamma_cv_error'])):.3g}, largest {float(np.nanmax(sur['gamma_cv_error'])):.3g}."
              if np.isfinite(sur["alpha_cv_error"]).any() else
              "Predictor band: the grid is too small to cross-validate the surrogate; its error is not in the band."),
    ]


def ensemble_blocks(fits: xr.Dataset, scenario: Scenario) -> list[Block]:
    """Realizations used, flagged cells, reached half-widths and power-law residuals per cell."""
    ox = scenario.oxide
    if "n_realizations" not in fits:
        return []
    used = fits["n_realizations"].max("xi").values
    flagged = fits["flagged"].values.astype(bool)
    if ox.ensemble == "adaptive":
        how = (f"adaptive: per (xi, lambda) from {ox.min_realizations} realizations in batches of "
               f"{scenario.compute.oxide_batch} until "
               f"the 95 % half-width of alpha (fast rule, exact for the geometric-mean fit) is within "
               f"{100 * ox.target_half_width:g} %, at most {ox.max_realizations}")
    else:
        how = f"fixed: {ox.n_realizations} realizations per lambda"
    cells = [f"(xi {float(x):g}, lambda {float(l):g})" for x, l in zip(*(
        fits[d].values[i] for d, i in zip(("xi", "lambda"), flagged.nonzero())))]
    hw_a, hw_g = fits["alpha_half_width"], fits["gamma_half_width"]
    rows = [
        [f"{float(lam):g}", int(n), f"{100 * float(hw_a.sel({'lambda': lam}).max()):.2f}",
         f"{float(hw_g.sel({'lambda': lam}).max()):.4f}", f"{float(fits['fit_residual_rms'].sel({'lambda': lam}).max()):.4f}",
         int(fits["flagged"].sel({"lambda": lam}).sum())]
        for lam, n in zip(fits["lambda"].values, used)
    ]
    return [
        Block("h2", "Ensemble: realizations used and reached confidence"),
        Block("p", f"Ensemble {how}; field period '{ox.period}'"
                   + (f" (k1 spans {ox.spectral_resolution:g} lattice steps)" if ox.period == "spectral" else "")
                   + f". {int(used.sum())} fields in all (the most any xi needed, summed over lambda); "
                   f"worst lambda {int(used.max())}. "
                   f"Flagged cells (stopped at the cap short of the target): {int(flagged.sum())}"
                   + (f": {', '.join(cells)}." if cells else ".")),
        Block("p", f"Largest bootstrap half-width over xi per lambda (alpha relative, gamma absolute); RMS log "
                   f"residual of the power law (largest over xi): overall max alpha half-width "
                   f"{100 * float(hw_a.max()):.2f} % (unflagged cells {100 * float(hw_a.where(~fits['flagged'].astype(bool)).max()):.2f} %)."),
        _table(["lambda", "realizations", "max alpha half-width %", "max gamma half-width",
                "max RMS log residual", "flagged"], rows),
        Block("p", _smoothness(fits)),
    ]


def _smoothness(fits: xr.Dataset) -> str:
    """Kinks of alpha in lambda: second differences of log alpha against their 95 % bound."""
    if fits.sizes["lambda"] < 3:
        return "Smoothness in lambda: fewer than three lambdas."
    log_alpha = np.log(fits["alpha"].transpose("xi", "lambda").values)
    se = fits["alpha_half_width"].transpose("xi", "lambda").values / 1.96  # ~ standard error of log alpha
    second = np.abs(log_alpha[:, 2:] - 2 * log_alpha[:, 1:-1] + log_alpha[:, :-2])
    bound = 1.96 * np.sqrt(se[:, 2:] ** 2 + 4 * se[:, 1:-1] ** 2 + se[:, :-2] ** 2)
    ratio = second / bound
    return (f"Smoothness in lambda at fixed xi: the largest |second difference of log alpha| is "
            f"{np.nanmax(second):.3f}; over its 95 % noise bound it reaches {np.nanmax(ratio):.2f}, and "
            f"{int(np.sum(ratio > 1))} of {ratio.size} interior points exceed 1 (about 5 % expected from noise "
            f"alone; the physical curvature of alpha(lambda) counts too where intervals are below 0.5 %).")


def surrogate_table_blocks(sur: xr.Dataset) -> list[Block]:
    """The surrogate's long tables: Table 3, Table 4 and the cross-validation scores (for the appendix)."""
    blocks = [Block("h2", "Table 3: fitted and surrogate alpha, gamma")]
    header = ["xi", "lambda"] + [f"{p} {c}" for p in PARAMETERS for c in ("fit", "surrogate", "err %")]
    rows = [[r["xi"], r["lambda"]] + [f"{r[f'{p}_{c}']:.4f}" if c != "error_percent" else f"{r[f'{p}_{c}']:+.2f}"
                                      for p in PARAMETERS for c in ("fit", "surrogate", "error_percent")]
            for r in table3_rows(sur)]
    blocks.append(_table(header, rows))
    blocks.append(Block("h2", "Table 4: surrogate coefficients (ascending powers)"))
    for p in PARAMETERS:
        transform, w_map = sg.split_spec(str(sur[f"{p}_coef_w"].attrs.get("transform", "identity")))
        what = f"ln {p}" if transform == "log" else p
        for axis, var in ((f"w = {sg.W_TEXT[w_map]}", "w"), ("z = -LN(1 - xi)", "z")):
            coef = sur[f"{p}_coef_{var}"].values
            blocks.append(Block("p", f"{what}, modes in {axis}:"))
            blocks.append(_table(["mode"] + [f"c{i}" for i in range(coef.shape[1])],
                                 [[k + 1] + [float(c) for c in row] for k, row in enumerate(coef)]))
    blocks.append(Block("h2", "Leave-one-line-out cross-validation of the surrogate"))
    blocks.append(Block("p", "Each lambda row and each xi column is left out in turn and predicted by a surrogate "
                             "fitted to the rest; the score is the RMS relative error (NaN: not enough lines)."))
    for p in PARAMETERS:
        if f"{p}_loo" in sur:
            loo = sur[f"{p}_loo"]
            blocks.append(Block("p", f"{p}: {loo.attrs.get('verdict', '')}"))
            blocks.append(_table(["order w \\ z"] + [str(int(z)) for z in loo.order_z.values],
                                 [[int(w)] + [float(v) for v in loo.sel(order_w=w).values] for w in loo.order_w.values]))
        elif f"{p}_cv_rms" in sur:
            score = sur[f"{p}_cv_rms"].values
            order = [i for i in np.argsort(score) if np.isfinite(score[i])][:12]
            keys = ("transform", "rank", "order_w", "order_z", "free_parameters")
            chosen = tuple(str(sur.attrs.get(f"{p}_{k}")) for k in keys)
            blocks.append(Block("p", f"{p}: the best-scoring candidates (chosen: the simplest within the tolerance of the best; marked *):"))
            blocks.append(_table(["", *keys, "CV RMS %"], [
                ["*" if tuple(str(sur[f"{p}_cv_{k}"].values[i]) for k in keys) == chosen else "",
                 *(sur[f"{p}_cv_{k}"].values[i] for k in keys), f"{100 * score[i]:.2f}"] for i in order]))
    return blocks
