"""``make report``: ``<data_dir>/report.md`` and ``report.html`` from one block structure.

The report is a list of blocks (heading, paragraph, table, image, preformatted text);
:func:`to_markdown` writes them as Markdown and :func:`to_html` renders that Markdown with
python-markdown, so the two files always agree. Sections whose input file is missing or stale say so
instead of failing, so a partial run still gets a report.
"""

from __future__ import annotations

import html
import json
import re
import time
from pathlib import Path
from typing import Any

import markdown
from markdown.extensions.toc import slugify, unique
import numpy as np
import xarray as xr
from scipy.stats import norm

from analysis.report_blocks import Block, table as _table
from analysis.report_physics import atlas_blocks, barber_blocks, bias_blocks, curve_blocks, validation_blocks
from pipeline import __version__
from pipeline.config import STAGE_INPUTS, Scenario, parameter_table
from pipeline.fitting import surrogate as sg
from pipeline.stages.table3 import PARAMETERS, table3_rows
from pipeline.store import StaleInputError, atomic_path, read_stage

__all__ = ["Block", "build_blocks", "to_markdown", "to_html", "write_report"]


#: Captions of the known figures, keyed by file stem; other figures are captioned by their stem.
CAPTIONS = {
    "fig3_bounds": "Fig. 3: Barber's clean and oxide-extended conductance bounds (Eqs. 8-9) and their geometric mean",
    "fig4_contact": "Fig. 4: Greenwood-Tripp solution of the rough Hertzian contact",
    "fig5_spots": "Fig. 5: discrete contact spots",
    "fig6_oxide": "Fig. 6: random oxide fields and thresholded oxides",
    "fig8_resistance": "Fig. 8: resistance R against force F: 16-84 % band, the fitted reduction (markers) and its power-law fit",
    "fig9_conductance": "Fig. 9: normalized conductance kappa' = 1/R' against F'",
    "fig10_alpha_gamma": "Fig. 10: fitted alpha and gamma (95 % bootstrap intervals) with their surrogate (Eq. 26) and its relative error",
    "fig10_realizations": "Fig. 10 (beside): realizations used per (xi, lambda) and alpha's reached 95 % half-width; x marks flagged cells",
    "fig11_barber": "Fig. 11: G2TOM against the p-average of the oxide-extended Barber bounds (Eq. 10)",
    "point_alpha_gamma": "Point-interaction model against Greenwood's closed form: alpha ratio and gamma shift",
    "barber_spots": "Barber's check: clean conductance over K / (E* rho*) against F for every spot discretization "
                    "(colours) and model (lines), from `g2tom bench --only spots`",
    "point_film": "Resistance against the oxide film's specific resistance r_f: clean to insulating",
}


#: Figures of the frontier benchmark, shown in "How fast, how accurate".
FRONTIER_FIGURES = {
    "frontier_contact": "Contact: error of the force and of the real contact area against solve time, per "
                        "tolerance (labels: radial nodes), and the paper's relaxed fixed point",
    "frontier_cube": "Cube: error of R, alpha and gamma against cube time per algorithm and crop tolerance, "
                     "and the spot maps rounded to float32",
    "frontier_ensemble": "Ensemble: relative half-width of the alpha and gamma intervals against the number of "
                         "realizations per (xi, lambda), time on the top axis",
}


def _frontier_blocks(data_dir: Path) -> list[Block]:
    """Section "How fast, how accurate": the frontier plots and a recommended setting per use."""
    blocks = [Block("h2", "How fast, how accurate")]
    summary = data_dir / "bench" / "frontier.json"
    if not summary.is_file():
        return blocks + [Block("p", "Not available: run `make bench` (or `g2tom bench --only frontier`).")]
    result = json.loads(summary.read_text())
    blocks.append(Block("p", "Each setting is timed (median of repeats) and its error measured against a reference "
                             "in the same run: contact against Newton to 1e-12 on 4x the radial nodes; the cube against "
                             "the dense gemm sum without cropping; the ensemble as the width of the bootstrap intervals. "
                             "The machine was shared: read times as ratios within this run."))
    rows = []
    for use, r in result.get("recommended", {}).items():
        numbers = [f"{r[k]:.3g}" for k in ("contact_seconds", "force_error", "area_error", "cube_seconds",
                                           "resistance_error", "alpha_error", "gamma_error")]
        rows.append([use, r["contact"], *numbers[:3], r["cube"], *numbers[3:], r["n_realizations"],
                     f"{r['ensemble_seconds']:.3g}", f"{r['interval_halfwidth']:.3g}",
                     "yes" if r["targets_met"] else "no"])
    blocks.append(Block("p", "Recommended setting per use: the fastest measured setting that meets the use's targets "
                             "(max relative force error, max relative error of R, worst relative interval half-width "
                             "of alpha and gamma over the (xi, lambda) subset)."))
    blocks.append(_table(["use", "contact", "time (s)", "force err", "area err", "cube", "time (s)", "R err",
                          "alpha err", "gamma err", "realizations", "time (s)", "CI half-width", "targets met"], rows))
    for stem, caption in FRONTIER_FIGURES.items():
        if (data_dir / "figures" / f"{stem}.png").is_file():
            blocks.append(Block("img", caption, src=f"figures/{stem}.png"))
    prefix = result.get("prefix")
    if prefix and "cells" in prefix:
        blocks.append(Block("p", (
            f"The adaptive ensemble's own cube, prefix by prefix: over {prefix['cells']} (xi, lambda) cells of "
            f"{prefix['count_min']} .. {prefix['count_max']} realizations (median {prefix['count_median']:g}, "
            f"{prefix['realizations']} in all), the fast rule's worst relative half-width of alpha falls from "
            f"{prefix['alpha_first_max']:.3g} at n = {prefix['first_n']} to {prefix['alpha_last_max']:.3g} at each "
            f"cell's count, and the absolute half-width of gamma from {prefix['gamma_first_max']:.3g} to "
            f"{prefix['gamma_last_max']:.3g}; the cube's {prefix['cube_seconds']:.4g} s prorated per realization "
            f"give the costliest cell {prefix['seconds_per_cell_max']:.3g} s.")))
        if (data_dir / "figures" / "frontier_prefix.png").is_file():
            blocks.append(Block("img", "Adaptive ensemble: the fast rule's half-widths of alpha and gamma against the "
                                       "first n realizations of every (xi, lambda) cell (dots: the cell's count), "
                                       "prorated cube time on the top axis", src="figures/frontier_prefix.png"))
    elif prefix:
        blocks.append(Block("p", prefix["note"] + "."))
    return blocks


def _stability_blocks(data_dir: Path) -> list[Block]:
    """Section "Stability map": per swept parameter, what converged and how hard it was."""
    blocks = [Block("h2", "Stability map")]
    path = data_dir / "bench" / "stability.nc"
    if not path.is_file():
        return blocks + [Block("p", "Not available: run `make bench` (or `g2tom bench --only stability`).")]
    with xr.open_dataset(path, decode_timedelta=False) as ds:
        ds = ds.load()
    status = ds["status"].values.astype(str)
    ran = np.isin(status, ("converged", "unconverged"))
    blocks.append(Block("p", f"{status.size} parameter sets far beyond the paper's scene ({ds.attrs.get('base', '')}): "
                             f"{int((status == 'converged').sum())} converged, {int((status == 'unconverged').sum())} "
                             f"did not, {int((status == 'refused').sum())} refused by validation with a message, "
                             f"{int((status == 'failed').sum())} failed. Of those solved, "
                             f"{int(ds['finite_nonnegative'].values[ran].sum())} have no NaN or negative value, "
                             f"{int(ds['force_monotone'].values[ran].sum())} a force growing with load and "
                             f"{int(ds['resistance_falls'].values[ran].sum())} a clean resistance falling with load; "
                             f"{int(ds['open_circuits'].values[ran].sum())} open circuits (+inf) were counted."))
    rows = []
    for parameter in dict.fromkeys(ds["parameter"].values.astype(str)):
        sel = ds["parameter"].values.astype(str) == parameter
        solved = sel & ran
        rows.append([parameter, ", ".join(ds["value"].values.astype(str)[sel]),
                     int((status[sel] == "converged").sum()), int((status[sel] != "converged").sum()),
                     int(ds["iterations"].values[solved].max()) if solved.any() else "",
                     float(np.nanmax(ds["residual"].values[solved])) if solved.any() else ""])
    blocks.append(_table(["parameter", "values", "converged", "not (refused/failed/unconverged)",
                          "max iterations", "worst residual"], rows))
    hertz = ds["parameter"].values.astype(str) == "hertz_limit"
    if hertz.any() and "roughness_parameter" in ds:
        pairs = ", ".join(f"{r:.3g} at sigma R*/a^2 = {a:.3g}" for r, a in
                          zip(ds["hertz_ratio"].values[hertz], ds["roughness_parameter"].values[hertz]))
        blocks.append(Block("p", f"Hertz limit: central pressure over the Hertz one at the same force {pairs} "
                                 f"(1 in the smooth limit)."))
    notes = [f"{p}={v}: {m}" for p, v, st, m in zip(ds["parameter"].values.astype(str), ds["value"].values.astype(str),
                                                    status, ds["message"].values.astype(str)) if st != "converged"]
    if notes:
        blocks.append(Block("pre", "\n".join(notes)))
    return blocks


def _figure_order(path: Path) -> tuple[Any, ...]:
    """Sort key that puts fig3 before fig10 (numbers compared as numbers)."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.stem))


def _load(data_dir: Path, stage: str, scenario: Scenario) -> tuple[xr.Dataset | None, list[Block]]:
    try:
        return read_stage(data_dir, stage, scenario), []
    except StaleInputError as exc:
        return None, [Block("p", f"Not available: {exc}")]


def _fit_blocks(fits: xr.Dataset, scenario: Scenario) -> list[Block]:
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


def _surrogate_model_blocks(sur: xr.Dataset) -> list[Block]:
    """Method, model sizes, errors and the closed formulas of the surrogate."""
    z_c = float(norm.ppf(0.5 + float(sur.attrs.get("fit_confidence", 0.95)) / 2.0))
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
        Block("p", "Predictor band (g2tom predict): three one-sigma half-widths in ln R, each reported: the "
                   "realization spread (16-84 %), the fit's interval (sqrt(s_a^2 + (ln F' s_g)^2) from alpha_ci, "
                   "gamma_ci) and the surrogate's local cross-validated error (sqrt(e_a^2 + (ln F' e_g)^2)), "
                   "combined in quadrature per side: lower = R exp(-total_lower), upper = R exp(total_upper). "
                   f"Local cross-validated error of ln alpha: median {100 * float(np.nanmedian(sur['alpha_cv_error'])):.2f} %, "
                   f"largest {100 * float(np.nanmax(sur['alpha_cv_error'])):.2f} %; of gamma: median "
                   f"{float(np.nanmedian(sur['gamma_cv_error'])):.3g}, largest {float(np.nanmax(sur['gamma_cv_error'])):.3g}."
              if np.isfinite(sur["alpha_cv_error"]).any() else
              "Predictor band: the grid is too small to cross-validate the surrogate; its error is not in the band."),
    ]


def _ensemble_blocks(fits: xr.Dataset, scenario: Scenario) -> list[Block]:
    """Realizations used, flagged cells, reached half-widths and power-law residuals per cell."""
    ox = scenario.oxide
    if "n_realizations" not in fits:
        return []
    used = fits["n_realizations"].max("xi").values
    flagged = fits["flagged"].values.astype(bool)
    if ox.ensemble == "adaptive":
        how = (f"adaptive: per (xi, lambda) from {ox.min_realizations} realizations in batches of {ox.batch} until "
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


def _surrogate_table_blocks(sur: xr.Dataset) -> list[Block]:
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


def _point_blocks(data_dir: Path) -> list[Block]:
    """alpha and gamma of both models on ``make compare``'s shared ensemble, and their ratio."""
    from analysis.figures_point import COMPARE, load_comparison

    try:
        fits = load_comparison(data_dir)
    except ValueError as exc:
        return [Block("h2", "Greenwood's closed form against the point-interaction model"), Block("p", f"Not available: {exc}")]
    if fits is None:
        return []
    g, p = fits["greenwood"], fits["point"]
    blocks = [
        Block("h2", "Greenwood's closed form against the point-interaction model"),
        Block("p", f"Both models on one ensemble of {g.attrs['oxide.n_realizations']} realizations "
                   f"(`make compare`, data under {COMPARE}/greenwood and {COMPARE}/point). Greenwood's form is "
                   "the Rayleigh quotient of the exact point-interaction system, so its resistance is an upper "
                   "bound: alpha_point / alpha_greenwood < 1 where gamma is unchanged."),
    ]
    rows = [["clean", "", float(g["alpha_clean"]), float(p["alpha_clean"]),
             float(p["alpha_clean"] / g["alpha_clean"]), float(g["gamma_clean"]), float(p["gamma_clean"]),
             float(p["gamma_clean"] - g["gamma_clean"])]]
    for xi in g["xi"].values:
        for lam in g["lambda"].values:
            a_g, a_p = float(g["alpha"].sel(xi=xi, **{"lambda": lam})), float(p["alpha"].sel(xi=xi, **{"lambda": lam}))
            c_g, c_p = float(g["gamma"].sel(xi=xi, **{"lambda": lam})), float(p["gamma"].sel(xi=xi, **{"lambda": lam}))
            rows.append([float(xi), float(lam), a_g, a_p, a_p / a_g, c_g, c_p, c_p - c_g])
    blocks.append(_table(["xi", "lambda", "alpha G", "alpha point", "ratio", "gamma G", "gamma point",
                          "gamma difference"], rows))
    return blocks


def _size(n_bytes: int) -> str:
    """A file size as text: bytes below 1 kB, else kB or MB with one decimal."""
    if n_bytes < 1000:
        return f"{n_bytes} B"
    return f"{n_bytes / 1e3:.1f} kB" if n_bytes < 1e6 else f"{n_bytes / 1e6:.1f} MB"


def _benchmark_blocks(data_dir: Path) -> list[Block]:
    """Section "Benchmarks": one line per raw record ``bench/*.json`` (name, path, size), not its contents.

    Parameters
    ----------
    data_dir : Path
        The report's folder; the paths are relative to it.

    Returns
    -------
    list of Block
        The heading and the list (or a note that there are no records).
    """
    blocks = [Block("h2", "Benchmarks")]
    files = sorted((data_dir / "bench").glob("*.json"))
    if not files:
        return blocks + [Block("p", "No benchmark records: run `make bench`.")]
    blocks.append(Block("p", "The raw records of `g2tom bench`, one JSON file per benchmark (relative to this report):"))
    items = []
    for path in files:
        relative = path.relative_to(data_dir).as_posix()
        items.append(f"{path.stem}: [{relative}]({relative}), {_size(path.stat().st_size)}")
    return blocks + [Block("list", rows=tuple((0, item) for item in items))]


def _timing_blocks(scenario: Scenario, data_dir: Path, report_seconds: float) -> list[Block]:
    """Wall times of the runs that made the files this report describes, figures and report too.

    ``timings.json`` keeps the last time of every step with the configuration hash it ran
    with; steps run with another configuration (an earlier or a different run) are left out.
    """
    blocks = [Block("h2", "Timings")]
    path = data_dir / "timings.json"
    try:
        recorded = json.loads(path.read_text()) if path.is_file() else {}
    except (OSError, ValueError):
        recorded = {}
    expected = {stage: scenario.config_hash(stage) for stage in STAGE_INPUTS}
    expected["figures"] = scenario.config_hash()
    rows = [[step, float(recorded[step]["seconds"]), recorded[step].get("finished", "")]
            for step in expected
            if isinstance(recorded.get(step), dict) and recorded[step].get("config_hash") == expected[step]]
    rows.append(["report", round(report_seconds, 3), "(this page)"])
    rows.append(["total", round(sum(r[1] for r in rows), 3), ""])
    blocks.append(_table(["step", "wall time (s)", "finished (UTC)"], rows))
    left_out = [step for step in expected if step not in {r[0] for r in rows}]
    if left_out:
        blocks.append(Block("p", "No time of this configuration's run for: " + ", ".join(left_out)
                            + " (run through another configuration, or not through the g2tom command)."))
    return blocks


def _parameter_blocks(scenario: Scenario) -> list[Block]:
    """Section "Parameters": every parameter of the scenario with its value, unit and meaning."""
    values = scenario.flat()
    return [Block("h2", "Parameters"), _table(
        ["parameter", "value", "unit", "meaning"],
        [[key, values[key], unit, doc] for key, _default, unit, _allowed, doc in parameter_table()],
    )]


def _span(values: np.ndarray, digits: int = 4) -> str:
    """``min-max`` of finite values as text (one value when they are equal)."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    return f"{lo:.{digits}g}" if lo == hi else f"{lo:.{digits}g}-{hi:.{digits}g}"


def _summary_blocks(scenario: Scenario, fits: xr.Dataset | None, sur: xr.Dataset | None,
                    validation: list[Block]) -> list[Block]:
    """Section "Summary": what was computed, the key numbers and how right they are.

    Parameters
    ----------
    scenario : Scenario
        The run's configuration (name, description, models).
    fits, sur : xarray.Dataset or None
        The fits and surrogate stages' outputs, None where not available.
    validation : list of Block
        The validation section's blocks; its bold paragraphs are the comparison's flag lines.

    Returns
    -------
    list of Block
        The heading and a list of statements, read from the stages' outputs (nothing recomputed).
    """
    items = [f"**Computed:** scenario '{scenario.name}': {scenario.description} (g2tom {__version__}, "
             f"configuration hash {scenario.config_hash()}); contact model {scenario.contact.model} with "
             f"{scenario.contact.spots} spots, resistance model {scenario.cube.model}."]
    if fits is None:
        items.append("**Not available:** the fits stage's output (run `g2tom fits`).")
    else:
        xi, lam = fits["xi"].values, fits["lambda"].values
        grid = f"{xi.size} xi ({_span(xi)}) x {lam.size} lambda ({_span(lam)})"
        if "force" in fits.coords and "force_normalized" in fits.coords:
            grid += (f"; {fits.sizes['delta']} load steps, F = {_span(fits['force'].values)} N, "
                     f"F' = {_span(fits['force_normalized'].values)}")
        if "n_realizations" in fits:
            grid += f"; realizations used per cell {_span(fits['n_realizations'].values)}"
        items.append(f"**Grid:** {grid}.")
        ci = {k: fits[f"{k}_clean_ci"].values for k in ("alpha", "gamma")}
        items.append(f"**Clean fit:** alpha = {float(fits['alpha_clean']):.4g} [{ci['alpha'][0]:.4g}, "
                     f"{ci['alpha'][1]:.4g}], gamma = {float(fits['gamma_clean']):.4g} [{ci['gamma'][0]:.4g}, "
                     f"{ci['gamma'][1]:.4g}] ({100 * scenario.fits.confidence:g} % intervals).")
        if "flagged" in fits:
            items.append(f"**Flagged cells** (stopped at the cap short of the confidence target): "
                         f"{int(fits['flagged'].sum())} of {fits['flagged'].size}.")
    if sur is not None:
        worst = ", ".join(f"{p} {100 * float(np.nanmax(np.abs(sur[f'{p}_relative_error'].values))):.2f} %"
                          for p in PARAMETERS)
        items.append(f"**Surrogate (Eq. 26):** worst relative error on the grid: {worst}.")
    label, flags = "", []
    for b in validation:
        if b.kind == "h3":
            label = b.text
        elif b.kind == "p" and b.text.startswith("**"):
            flags.append(f"Against the full elastic contact ({label}): {b.text}")
    items += flags or ["Against the full elastic contact: not run (`make validate`)."]
    return [Block("h2", "Summary"), Block("list", rows=tuple((0, item) for item in items))]


def _contents_blocks(before: list[Block], after: list[Block]) -> list[Block]:
    """Section "Contents": links to the sections in ``after`` (and the Appendix's subsections).

    Parameters
    ----------
    before, after : list of Block
        The report's blocks before and after the contents; the anchors count every heading in
        order, as python-markdown's ``toc`` extension (and GitHub) number repeated titles.

    Returns
    -------
    list of Block
        The heading and a nested list of ``[title](#anchor)`` links.
    """
    contents = Block("h2", "Contents")
    ids: set[str] = set()
    items, section = [], ""
    for b in [*before, contents, *after]:
        if b.kind not in ("h1", "h2", "h3", "h4"):
            continue
        anchor = unique(slugify(b.text, "-"), ids)
        if b.kind == "h2":
            section = b.text
        if b.kind == "h2" and b is not contents:
            items.append((0, f"[{b.text}](#{anchor})"))
        elif b.kind == "h3" and section == "Appendix":
            items.append((1, f"[{b.text}](#{anchor})"))
    return [contents, Block("list", rows=tuple(items))]


def _demote(blocks: list[Block]) -> list[Block]:
    """The blocks with every heading one level lower (h2 to h3, h3 to h4), to nest them in a section."""
    lower = {"h2": "h3", "h3": "h4"}
    return [Block(lower.get(b.kind, b.kind), b.text, b.rows, b.src) for b in blocks]


def build_blocks(scenario: Scenario, data_dir: str | Path, started: float | None = None) -> list[Block]:
    """The whole report as blocks, in reading order (figures linked relative to ``data_dir``).

    Title, Summary (what was computed, the key numbers, how right they are), Contents, Figures,
    the physics sections, then an Appendix with the long tables and the list of raw benchmark
    records.

    Parameters
    ----------
    scenario : Scenario
        The run's configuration.
    data_dir : str or Path
        The folder of the stage outputs, where the report is written.
    started : float, optional
        A :func:`time.perf_counter` value: when the report began, for its own row in the
        timings table; default: now.

    Returns
    -------
    list of Block
        The report's blocks.
    """
    started = time.perf_counter() if started is None else started
    data_dir = Path(data_dir)
    fits, missing_fits = _load(data_dir, "fits", scenario)
    sur, missing_sur = _load(data_dir, "surrogate", scenario)
    validation = validation_blocks(data_dir)
    physics = missing_fits if fits is None else (
        _fit_blocks(fits, scenario) + _ensemble_blocks(fits, scenario) + curve_blocks(fits))
    physics += missing_sur if sur is None else _surrogate_model_blocks(sur)
    physics += bias_blocks(data_dir) + barber_blocks(data_dir, scenario) + validation
    physics += atlas_blocks(data_dir) + _point_blocks(data_dir)
    figures = sorted((p for p in (data_dir / "figures").glob("*.png") if p.stem not in FRONTIER_FIGURES),
                     key=_figure_order)
    body = [Block("h2", "Figures")]
    body += [Block("img", CAPTIONS.get(p.stem, p.stem), src=p.relative_to(data_dir).as_posix()) for p in figures]
    if not figures:
        body.append(Block("p", "No figures: run `g2tom figures` first."))
    appendix = [] if sur is None else _surrogate_table_blocks(sur)
    appendix += _frontier_blocks(data_dir) + _stability_blocks(data_dir) + _parameter_blocks(scenario)
    appendix += _benchmark_blocks(data_dir)
    appendix += _timing_blocks(scenario, data_dir, time.perf_counter() - started)  # last: it times the rest
    body += physics + [Block("h2", "Appendix"), Block("p", "The long tables and the raw records.")]
    body += _demote(appendix)
    head = [Block("h1", f"g2tom report: scenario '{scenario.name}'")]
    head += _summary_blocks(scenario, fits, sur, validation)
    return head + _contents_blocks(head, body) + body


def _md_text(text: str) -> str:
    """Inline text as Markdown: a single ``*`` (E*, R*, rho*) escaped outside code spans, so that
    only ``**bold**`` and backtick code spans are markup."""
    parts = re.split(r"(`[^`]*`)", text)
    return "".join(part if k % 2 else re.sub(r"(?<!\*)\*(?!\*)", r"\\*", part) for k, part in enumerate(parts))


def _md_cell(text: str) -> str:
    """A table cell as Markdown: inline text with ``|`` escaped."""
    return _md_text(text).replace("|", "\\|")


def to_markdown(blocks: list[Block]) -> str:
    """Render blocks as Markdown."""
    out: list[str] = []
    for b in blocks:
        if b.kind in ("h1", "h2", "h3", "h4"):
            out.append("#" * int(b.kind[1]) + " " + _md_text(b.text))
        elif b.kind == "p":
            out.append(_md_text(b.text))
        elif b.kind == "pre":
            out.append("```\n" + b.text + "\n```")
        elif b.kind == "list":
            out.append("\n".join("    " * int(level) + "- " + _md_text(text) for level, text in b.rows))
        elif b.kind == "img":
            caption = _md_text(b.text)
            out.append(f"![{caption}]({b.src})\n\n*{caption}*")
        elif b.kind == "table":
            header, *rows = b.rows
            lines = ["| " + " | ".join(_md_cell(c) for c in header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in rows]
            out.append("\n".join(lines))
        else:
            raise ValueError(f"unknown block kind {b.kind!r}")
    return "\n\n".join(out) + "\n"


#: The page's style: a readable measure, tables that scroll sideways, figures and formulas that fit.
STYLE = ("body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em;line-height:1.4}"
         "table{display:block;overflow-x:auto;border-collapse:collapse;margin:1em 0}"
         "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
         "img{max-width:100%}"
         "code,pre{overflow-wrap:anywhere;white-space:pre-wrap}"
         "pre{background:#f6f6f6;padding:0.5em}")


def to_html(blocks: list[Block], title: str) -> str:
    """Render blocks as a standalone HTML page, through their Markdown.

    Parameters
    ----------
    blocks : list of Block
        The report's blocks.
    title : str
        The page's ``<title>``.

    Returns
    -------
    str
        The page: :func:`to_markdown`'s text rendered by python-markdown (``tables``, ``toc``
        for the headings' ids, ``fenced_code``), with :data:`STYLE`.
    """
    body = markdown.markdown(to_markdown(blocks), extensions=["tables", "toc", "fenced_code"])
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style></head><body>\n{body}\n</body></html>\n")


def write_report(scenario: Scenario, data_dir: str | Path) -> list[Path]:
    """Write ``report.md`` and ``report.html`` under ``data_dir`` atomically; returns both paths."""
    started = time.perf_counter()
    data_dir = Path(data_dir)
    blocks = build_blocks(scenario, data_dir, started)
    outputs = {
        data_dir / "report.md": to_markdown(blocks),
        data_dir / "report.html": to_html(blocks, f"g2tom report: {scenario.name}"),
    }
    for path, text in outputs.items():
        with atomic_path(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return list(outputs)
