"""The accuracy–time frontier: what each numerical setting costs and what it buys.

Three sweeps, each against a reference computed in the same process:

* contact: Newton on graded grids of 20..720 radial nodes at tolerances 1e-4..1e-10, and the
  paper's relaxed fixed point (zeta, epsilon) on its 20-node uniform grid and on the default
  grid; error of the force and of the real contact area (the integral of A* over the plane)
  against a grid-converged run (4x the scenario's nodes, Newton to 1e-12); time of the solve
  (median of :data:`REPEATS`).
* cube: interaction algorithm x crop tolerance, and the spot maps rounded to float32 (the
  stage computes in float64; this measures what float32 storage would cost), on a subset of
  the (xi, lambda) grid; error of R and of the fitted alpha and gamma against the dense
  ``gemm`` sum without cropping, and time of the cube build.
* ensemble: the first n = 25..N realizations of one ensemble (today's fixed counts) against
  the width of the bootstrap intervals of alpha and gamma per (xi, lambda), and the time
  (oxide and cube prorated to n from one timed run of N, plus the timed fits).
* prefix (from an existing adaptive ``<data_dir>/cube.nc``, else skipped with a note): per
  (xi, lambda), the fast rule's half-widths of alpha and gamma (:func:`pipeline.stages.cube_rounds.half_widths`)
  at log-spaced prefixes n = 50 .. the cell's count, and the cube time prorated to n.

``make bench`` writes ``<data_dir>/bench/frontier.nc`` (:func:`write`) and its figures
``frontier_contact.png``, ``frontier_cube.png``, ``frontier_ensemble.png`` (and
``frontier_prefix.png`` with a prefix curve) under ``<data_dir>/figures``; :func:`recommend` turns the sweeps into a setting per use.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any, Callable

import numpy as np
import xarray as xr

from pipeline.compute import ComputeOptions
from pipeline.bench.timing import median_time
from pipeline.config import Scenario
from pipeline.physics import greenwood_tripp as gt
from pipeline.store import atomic_path

__all__ = ["run", "contact_frontier", "cube_frontier", "ensemble_frontier", "prefix_counts", "prefix_curve",
           "adaptive_prefix", "prefix_summary", "recommend", "write", "plot", "USES"]

REPEATS = 3
#: Radial node counts and Newton tolerances of the contact sweep.
NODES = (20, 60, 120, 240, 480, 720)
TOLERANCES = (1e-4, 1e-7, 1e-10)
#: Cube sweep: algorithms and crop tolerances; (xi, lambda) subset and realizations.
METHODS = ("folded", "fft", "gemm")
CROPS = (0.0, 1e-6, 1e-4, 1e-2)
SUBSET = {"xi": [0.2, 0.5, 0.8], "lambda_": [3.0, 11.0, 23.0]}
CUBE_REALIZATIONS = 40
#: Ensemble sweep: the largest ensemble and the prefixes fitted.
ENSEMBLE_REALIZATIONS = 400
ENSEMBLE_COUNTS = (25, 50, 100, 200, 400)
#: Prefix curve of an adaptive cube: the smallest prefix and the points per (xi, lambda).
PREFIX_FROM = 50
PREFIX_POINTS = 12
#: Uses and their targets: contact force error, cube R error, relative interval half-width.
USES: dict[str, dict[str, float]] = {
    "quick look": {"force_error": 1e-3, "resistance_error": 1e-3, "interval": 0.10},
    "paper-grade": {"force_error": 1e-5, "resistance_error": 1e-5, "interval": 0.05},
    "publication-grade": {"force_error": 1e-7, "resistance_error": 1e-8, "interval": 0.025},
}


def _median_time(fn: Callable[[], Any], repeats: int | None = None) -> tuple[float, Any]:
    """Median wall time (s) of ``repeats`` (default :data:`REPEATS`) calls of ``fn`` and its result."""
    return median_time(fn, REPEATS if repeats is None else repeats)


def _replace(scenario: Scenario, section: str, **changes: Any) -> Scenario:
    return dataclasses.replace(scenario, **{section: dataclasses.replace(getattr(scenario, section), **changes)})


def _force_and_area(scenario: Scenario, r: np.ndarray, sols: list) -> tuple[np.ndarray, np.ndarray]:
    """Force (N) and real contact area (m^2) of every approach."""
    from pipeline.stages import contact

    f = contact.fields(scenario, r, sols)
    return f["force"], f["area"] @ gt.force_weights(r)


def contact_frontier(scenario: Scenario) -> list[dict[str, Any]]:
    """Every contact setting with its time (s) and largest relative force and area errors."""
    from pipeline.stages import contact

    n_ref = 4 * scenario.contact.n_radial
    r, sols = contact.solve_scenario(scenario, solver="newton", n_radial=n_ref, tolerance=1e-12)
    ref_force, ref_area = _force_and_area(scenario, r, sols)
    settings = [("newton", n, "graded", tol) for n in NODES for tol in TOLERANCES]
    settings += [("fixed_point", 20, "uniform", scenario.contact.fixed_point_tolerance),
                 ("fixed_point", scenario.contact.n_radial, "graded", scenario.contact.fixed_point_tolerance)]
    rows = []
    for solver, n, grid, tol in settings:
        s = _replace(scenario, "contact", radial_grid=grid)
        seconds, (r, sols) = _median_time(
            lambda s=s, n=n, tol=tol, solver=solver: contact.solve_scenario(
                s, solver=solver, n_radial=n, tolerance=tol if solver == "newton" else None))
        force, area = _force_and_area(s, r, sols)
        rows.append({
            "solver": solver, "n_radial": n, "radial_grid": grid, "tolerance": tol, "seconds": seconds,
            "force_error": float(np.max(np.abs(force / ref_force - 1))),
            "area_error": float(np.max(np.abs(area / ref_area - 1))),
            "converged": all(x.converged for x in sols),
        })
    return rows


def _max_rel(value: np.ndarray, reference: np.ndarray) -> float:
    """Largest relative difference over entries finite in both; inf if the open circuits differ."""
    finite = np.isfinite(reference)
    if not np.array_equal(finite, np.isfinite(value)):
        return math.inf
    return float(np.max(np.abs(value[finite] / reference[finite] - 1))) if finite.any() else 0.0


def _float32(contact_ds: xr.Dataset) -> xr.Dataset:
    out = contact_ds.copy()
    for name in ("spot_radius", "spot_area"):
        out[name] = out[name].astype(np.float32).astype(np.float64)
    return out


def cube_frontier(scenario: Scenario) -> list[dict[str, Any]]:
    """Every (algorithm, crop tolerance, precision) with its time and errors in R, alpha, gamma."""
    from pipeline.stages import contact, cube, fits, oxide

    base = _replace(_replace(scenario, "oxide", **SUBSET, ensemble="fixed", n_realizations=CUBE_REALIZATIONS),
                    "fits", n_bootstrap=10)
    quiet = ComputeOptions(progress=False)
    contact_ds, oxide_ds = contact.build(base), oxide.build(base, quiet)

    def build(method: str, crop: float, spots: xr.Dataset) -> tuple[float, xr.Dataset, xr.Dataset]:
        s = _replace(base, "cube", method=method, crop_tolerance=crop)
        seconds, ds = _median_time(lambda: cube.build(s, spots, oxide_ds, quiet))
        return seconds, ds, fits.build(s, ds)

    _, ref, ref_fit = build("gemm", 0.0, contact_ds)
    settings = [(m, c, "float64") for m in METHODS for c in CROPS]
    settings += [("folded", c, "float32") for c in (0.0, base.cube.crop_tolerance)]
    rows = []
    for method, crop, precision in settings:
        spots = contact_ds if precision == "float64" else _float32(contact_ds)
        seconds, ds, fit = build(method, crop, spots)
        rows.append({
            "method": method, "crop_tolerance": crop, "precision": precision, "seconds": seconds,
            "simulations": int(ds["resistance"].size),
            "resistance_error": _max_rel(ds["resistance"].values, ref["resistance"].values),
            "alpha_error": _max_rel(fit["alpha"].values, ref_fit["alpha"].values),
            "gamma_error": _max_rel(fit["gamma"].values, ref_fit["gamma"].values),
        })
    return rows


def ensemble_frontier(scenario: Scenario) -> xr.Dataset:
    """Interval widths of alpha and gamma and time against the number of realizations."""
    from pipeline.stages import contact, cube, fits, oxide

    base = _replace(scenario, "oxide", **SUBSET, ensemble="fixed", n_realizations=ENSEMBLE_REALIZATIONS)
    quiet = ComputeOptions(progress=False)
    contact_ds = contact.build(base)
    t_oxide, oxide_ds = _median_time(lambda: oxide.build(base, quiet), repeats=1)
    t_cube, cube_ds = _median_time(lambda: cube.build(base, contact_ds, oxide_ds, quiet), repeats=1)
    counts = [n for n in ENSEMBLE_COUNTS if n <= ENSEMBLE_REALIZATIONS]
    widths = {k: [] for k in ("alpha", "gamma")}
    values = {k: [] for k in ("alpha", "gamma")}
    seconds = []
    for n in counts:
        s = _replace(base, "oxide", n_realizations=n)
        head = cube_ds.isel(realization=slice(0, n))
        head["n_realizations"] = np.minimum(head["n_realizations"], n)
        t_fit, fit = _median_time(lambda s=s, head=head: fits.build(s, head), repeats=1)
        seconds.append((t_oxide + t_cube) * n / ENSEMBLE_REALIZATIONS + t_fit)
        for k in widths:
            ci = fit[f"{k}_ci"].transpose("xi", "lambda", ...).values
            widths[k].append((ci[..., 1] - ci[..., 0]) / 2 / np.abs(fit[k].transpose("xi", "lambda").values))
            values[k].append(fit[k].transpose("xi", "lambda").values)
    dims = ("n_realizations", "xi", "lambda")
    ds = xr.Dataset(
        {
            "alpha_halfwidth": (dims, np.array(widths["alpha"]), {"long_name": "relative half-width of the alpha interval", "units": "1"}),
            "gamma_halfwidth": (dims, np.array(widths["gamma"]), {"long_name": "relative half-width of the gamma interval", "units": "1"}),
            "alpha": (dims, np.array(values["alpha"]), {"long_name": "fitted alpha", "units": "1"}),
            "gamma": (dims, np.array(values["gamma"]), {"long_name": "fitted gamma", "units": "1"}),
            "ensemble_seconds": (("n_realizations",), np.array(seconds),
                                 {"long_name": "oxide + cube time prorated to n, plus the fits time", "units": "s"}),
        },
        coords={
            "n_realizations": ("n_realizations", np.array(counts), {"long_name": "realizations fitted", "units": "1"}),
            "xi": ("xi", np.array(base.oxide.xi), {"long_name": "oxide fraction", "units": "1"}),
            "lambda": ("lambda", np.array(base.oxide.lambda_), {"long_name": "normalized correlation length", "units": "1"}),
        },
        attrs={"confidence": base.fits.confidence, "n_bootstrap": base.fits.n_bootstrap},
    )
    return ds


def prefix_counts(count: int) -> np.ndarray:
    """:data:`PREFIX_POINTS` prefixes log-spaced from ``min(PREFIX_FROM, count)`` to ``count`` (rounded)."""
    return np.round(np.geomspace(min(PREFIX_FROM, count), count, PREFIX_POINTS)).astype(np.int64)


def prefix_curve(scenario: Scenario, cube_ds: xr.Dataset, cube_seconds: float) -> xr.Dataset:
    """The fast rule's half-widths and the prorated time at prefixes of every (xi, lambda) of a cube.

    Parameters
    ----------
    scenario
        The scenario the cube was built with (``fits.min_force`` and ``fits.confidence`` set the rule).
    cube_ds
        An adaptive cube: ``resistance`` (xi, lambda, delta, realization), NaN beyond
        ``n_realizations`` (xi, lambda); ``force`` and ``force_normalized`` (delta).
    cube_seconds
        Wall time of the cube stage that built ``cube_ds`` (s), spread evenly over every
        realization of every cell.

    Returns
    -------
    xarray.Dataset
        ``prefix_n``, ``prefix_alpha_halfwidth`` (relative), ``prefix_gamma_halfwidth``
        (absolute) and ``prefix_seconds``, each (cube_xi, cube_lambda, prefix_step); the last
        step is the cell's count, where the half-widths equal the cube's ``rule_*_half_width``.
    """
    from pipeline.stages import cube_rounds

    rule = cube_rounds.stopping_rule(scenario, cube_ds["force"].values, cube_ds["force_normalized"].values)
    resistance = cube_ds["resistance"].transpose("xi", "lambda", "delta", "realization").values
    counts = cube_ds["n_realizations"].transpose("xi", "lambda").values.astype(np.int64)
    per_realization = cube_seconds / counts.sum()
    shape = (*counts.shape, PREFIX_POINTS)
    n = np.zeros(shape, np.int64)
    alpha, gamma = np.full(shape, np.nan), np.full(shape, np.nan)
    for i, j in np.ndindex(counts.shape):
        n[i, j] = prefix_counts(int(counts[i, j]))
        a, g = cube_rounds.half_widths(resistance[i, j][None, :, : counts[i, j]], rule)
        alpha[i, j], gamma[i, j] = a[0, n[i, j] - 1], g[0, n[i, j] - 1]
    dims = ("cube_xi", "cube_lambda", "prefix_step")
    return xr.Dataset(
        {
            "prefix_n": (dims, n, {"long_name": "realizations in the prefix of the adaptive cube's cell", "units": "1"}),
            "prefix_alpha_halfwidth": (dims, alpha, {
                "long_name": "fast-rule relative half-width of alpha with the first prefix_n realizations",
                "units": "1"}),
            "prefix_gamma_halfwidth": (dims, gamma, {
                "long_name": "fast-rule absolute half-width of gamma with the first prefix_n realizations",
                "units": "1"}),
            "prefix_seconds": (dims, n * per_realization, {
                "long_name": "cube stage time prorated to prefix_n realizations of the cell", "units": "s"}),
            "prefix_count": (dims[:2], counts, {"long_name": "realizations of the adaptive cube's cell", "units": "1"}),
        },
        coords={
            "cube_xi": ("cube_xi", cube_ds["xi"].values, {"long_name": "oxide fraction (adaptive cube)", "units": "1"}),
            "cube_lambda": ("cube_lambda", cube_ds["lambda"].values,
                            {"long_name": "normalized correlation length (adaptive cube)", "units": "1"}),
            "prefix_step": ("prefix_step", np.arange(PREFIX_POINTS), {"long_name": "prefix index", "units": "1"}),
        },
        attrs={"prefix_cube_seconds": cube_seconds},
    )


def adaptive_prefix(scenario: Scenario, data_dir: str | Path) -> tuple[xr.Dataset | None, str]:
    """:func:`prefix_curve` of ``<data_dir>/cube.nc`` when it is an adaptive cube of ``scenario``.

    Returns
    -------
    tuple
        The curve (None when skipped) and a one-line note saying where it came from or why not.
    """
    from pipeline import store

    problem = store.stage_problem(data_dir, "cube", scenario)
    if problem:
        return None, f"prefix curve skipped: {problem}"
    path = store.stage_path(data_dir, "cube")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        if ds.attrs.get("ensemble") != "adaptive":
            return None, f"prefix curve skipped: {path} is a fixed ensemble (oxide.ensemble = \"fixed\")"
        cube_ds = ds[["resistance", "n_realizations"]].load()  # with the force coordinates
        rule_target = float(ds.attrs["rule_target_half_width"])
        config_hash = ds.attrs.get("config_hash")
    timings = Path(data_dir) / "timings.json"
    entry = json.loads(timings.read_text()).get("cube", {}) if timings.is_file() else {}
    if "seconds" not in entry or entry.get("config_hash") != config_hash:
        return None, f"prefix curve skipped: no cube time of {path} in {timings}"
    curve = prefix_curve(scenario, cube_ds, float(entry["seconds"]))
    curve.attrs["prefix_rule_target"] = rule_target
    return curve, (f"prefix curve of {path}: {int(curve['prefix_count'].sum())} realizations over "
                   f"{curve['prefix_count'].size} cells, cube time {entry['seconds']:.4g} s prorated")


def prefix_summary(prefix: xr.Dataset | None, note: str) -> dict[str, Any]:
    """JSON-ready summary of a prefix curve for the report: its note and, if any, its extremes."""
    if prefix is None:
        return {"note": note}
    first = {k: prefix[f"prefix_{k}_halfwidth"].isel(prefix_step=0) for k in ("alpha", "gamma")}
    last = {k: prefix[f"prefix_{k}_halfwidth"].isel(prefix_step=-1) for k in ("alpha", "gamma")}
    counts = prefix["prefix_count"].values
    return {
        "note": note, "cells": int(counts.size), "realizations": int(counts.sum()),
        "count_min": int(counts.min()), "count_median": float(np.median(counts)), "count_max": int(counts.max()),
        "first_n": int(prefix["prefix_n"].isel(prefix_step=0).min()),
        "alpha_first_max": float(first["alpha"].max()), "alpha_last_max": float(last["alpha"].max()),
        "gamma_first_max": float(first["gamma"].max()), "gamma_last_max": float(last["gamma"].max()),
        "cube_seconds": float(prefix.attrs["prefix_cube_seconds"]),
        "seconds_per_cell_max": float(prefix["prefix_seconds"].isel(prefix_step=-1).max()),
    }


def _table(rows: list[dict[str, Any]], dim: str) -> xr.Dataset:
    """Rows of equal keys as a dataset over ``dim`` (strings stay strings)."""
    units = {"seconds": "s", "n_radial": "1"}
    data = {}
    for key in rows[0]:
        values = np.array([r[key] for r in rows])
        if values.dtype == bool:
            values = values.astype(np.int8)
        data[f"{dim}_{key}"] = ((dim,), values, {"long_name": f"{dim} sweep: {key.replace('_', ' ')}",
                                                 "units": units.get(key, "1")})
    return xr.Dataset(data, coords={dim: (dim, np.arange(len(rows)), {"long_name": f"{dim} setting", "units": "1"})})


def recommend(contact_rows: list[dict[str, Any]], cube_rows: list[dict[str, Any]],
              ensemble: xr.Dataset) -> dict[str, dict[str, Any]]:
    """The fastest setting of each sweep that meets each use's target, with its time and error."""
    out: dict[str, dict[str, Any]] = {}
    for use, target in USES.items():
        ok_contact = [r for r in contact_rows if r["solver"] == "newton" and r["force_error"] <= target["force_error"]]
        c = min(ok_contact, key=lambda r: r["seconds"]) if ok_contact else min(contact_rows, key=lambda r: r["force_error"])
        ok_cube = [r for r in cube_rows if r["precision"] == "float64" and r["resistance_error"] <= target["resistance_error"]]
        k = min(ok_cube, key=lambda r: r["seconds"]) if ok_cube else min(cube_rows, key=lambda r: r["resistance_error"])
        worst = np.maximum(ensemble["alpha_halfwidth"].max(("xi", "lambda")), ensemble["gamma_halfwidth"].max(("xi", "lambda")))
        meets = ensemble["n_realizations"].values[worst.values <= target["interval"]]
        n = int(meets[0]) if meets.size else int(ensemble["n_realizations"].values[-1])
        out[use] = {
            "contact": f"n_radial={c['n_radial']} tolerance={c['tolerance']:g}",
            "contact_seconds": c["seconds"], "force_error": c["force_error"], "area_error": c["area_error"],
            "cube": f"method={k['method']} crop_tolerance={k['crop_tolerance']:g}",
            "cube_seconds": k["seconds"], "resistance_error": k["resistance_error"],
            "alpha_error": k["alpha_error"], "gamma_error": k["gamma_error"],
            "n_realizations": n, "ensemble_seconds": float(ensemble["ensemble_seconds"].sel(n_realizations=n)),
            "interval_halfwidth": float(worst.sel(n_realizations=n)),
            "targets_met": bool(ok_contact and ok_cube and meets.size),
        }
    return out


def write(contact_rows: list[dict[str, Any]], cube_rows: list[dict[str, Any]], ensemble: xr.Dataset,
          target: str | Path, prefix: xr.Dataset | None = None, prefix_note: str = "") -> Path:
    """All sweeps (and the adaptive cube's ``prefix`` curve, if any) in one labelled netCDF file, atomically."""
    parts = [_table(contact_rows, "contact"), _table(cube_rows, "cube"), ensemble]
    ds = xr.merge(parts + ([prefix] if prefix is not None else []), combine_attrs="drop_conflicts")
    if prefix is not None:
        ds.attrs.update({k: v for k, v in prefix.attrs.items() if k.startswith("prefix_")})
    if prefix_note:
        ds.attrs["prefix_note"] = prefix_note
    ds.attrs.update({"title": "g2tom accuracy-time frontier", "Conventions": "CF-1.10",
                     "contact_reference": "Newton to 1e-12 on 4x the scenario's radial nodes",
                     "cube_reference": "gemm, crop_tolerance 0, float64",
                     "machine_note": "wall times on a shared machine: compare ratios within one run"})
    target = Path(target)
    with atomic_path(target) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    return target


def plot(frontier: xr.Dataset, out_dir: str | Path) -> list[Path]:
    """``frontier_contact.png``, ``frontier_cube.png``, ``frontier_ensemble.png`` under ``out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator

    def plain_time_axis(ax: Any) -> None:
        """Time ticks at 1, 2, 5 x 10^k with plain labels, none on the minor ticks."""
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    floor = 1e-16

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    solver = frontier["contact_solver"].values
    for ax, err in zip(axes, ("force_error", "area_error")):
        for tol in TOLERANCES:
            sel = (solver == "newton") & np.isclose(frontier["contact_tolerance"].values, tol)
            ax.loglog(frontier["contact_seconds"].values[sel], np.maximum(frontier[f"contact_{err}"].values[sel], floor),
                      "o-", label=f"Newton, tol {tol:g}")
            for x, y, n in zip(frontier["contact_seconds"].values[sel], frontier[f"contact_{err}"].values[sel],
                               frontier["contact_n_radial"].values[sel]):
                if tol == TOLERANCES[-1]:
                    ax.annotate(str(n), (x, max(y, floor)), fontsize=7, xytext=(3, 3), textcoords="offset points")
        fp = solver == "fixed_point"
        ax.loglog(frontier["contact_seconds"].values[fp], np.maximum(frontier[f"contact_{err}"].values[fp], floor),
                  "s", color="k", label="relaxed fixed point (20 uniform; default grid)")
        plain_time_axis(ax)
        ax.set_xlabel("solve time, s")
        ax.set_ylabel(f"max relative {err.replace('_error', '')} error")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Contact: radial nodes (labels) and tolerance against error and time")
    paths.append(out_dir / "frontier_contact.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), constrained_layout=True)
    for ax, err in zip(axes, ("resistance_error", "alpha_error", "gamma_error")):
        for method in METHODS:
            for precision, marker in (("float64", "o-"), ("float32", "x")):
                sel = (frontier["cube_method"].values == method) & (frontier["cube_precision"].values == precision)
                if sel.any():
                    ax.loglog(frontier["cube_seconds"].values[sel], np.maximum(frontier[f"cube_{err}"].values[sel], floor),
                              marker, label=f"{method} {precision}")
        plain_time_axis(ax)
        ax.set_xlabel("cube time, s")
        ax.set_ylabel(f"max relative {err.replace('_error', '')} error")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Cube: algorithm, crop tolerance (0, 1e-6, 1e-4, 1e-2 along each line) and precision")
    paths.append(out_dir / "frontier_cube.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    n = frontier["n_realizations"].values
    for ax, name in zip(axes, ("alpha", "gamma")):
        width = frontier[f"{name}_halfwidth"]
        for xi in width["xi"].values:
            for lam in width["lambda"].values:
                ax.loglog(n, width.sel(xi=xi, **{"lambda": lam}).values, "-", alpha=0.6, label=f"xi {xi:g}, lambda {lam:g}")
        ax.loglog(n, width.max(("xi", "lambda")).values[0] * np.sqrt(n[0] / n), "k--", label="n^-1/2")
        ax.set_xlabel("realizations")
        ax.set_ylabel(f"relative half-width of the {name} interval")
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xticks(n, [str(int(v)) for v in n])
        ax.xaxis.set_minor_locator(NullLocator())
        top = ax.secondary_xaxis("top", functions=(lambda x: x, lambda x: x))
        top.set_xticks(n, [f"{t:.2g} s" for t in frontier["ensemble_seconds"].values], fontsize=7)
        top.xaxis.set_minor_locator(NullLocator())
    axes[1].legend(fontsize=6, ncol=2)
    fig.suptitle("Ensemble: interval width against realizations (top: time)")
    paths.append(out_dir / "frontier_ensemble.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    if "prefix_n" in frontier:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
        lambdas = frontier["cube_lambda"].values
        colors = plt.cm.viridis(np.linspace(0, 1, lambdas.size))
        per_realization = float(frontier.attrs["prefix_cube_seconds"]) / float(frontier["prefix_count"].sum())
        for ax, name in zip(axes, ("alpha", "gamma")):
            width = frontier[f"prefix_{name}_halfwidth"].transpose("cube_xi", "cube_lambda", "prefix_step").values
            n = frontier["prefix_n"].transpose("cube_xi", "cube_lambda", "prefix_step").values
            for j, lam in enumerate(lambdas):
                for i in range(n.shape[0]):
                    ax.loglog(n[i, j], width[i, j], "-", color=colors[j], lw=0.8, alpha=0.7,
                              label=f"lambda {lam:g}" if i == 0 else None)
                ax.loglog(n[:, j, -1], width[:, j, -1], "o", color=colors[j], ms=3)
            if name == "alpha" and "prefix_rule_target" in frontier.attrs:
                ax.axhline(frontier.attrs["prefix_rule_target"], color="k", ls="--", lw=0.8,
                           label="the rule's stopping target")
            ax.set_xlabel("realizations of the cell (dots: the adaptive ensemble's count)")
            ax.set_ylabel(f"fast-rule {'relative' if name == 'alpha' else 'absolute'} half-width of {name}")
            ax.grid(True, which="major", alpha=0.3)
            top = ax.secondary_xaxis("top", functions=(lambda x: x * per_realization, lambda t: t / per_realization))
            top.set_xlabel("cube time prorated to n, s")
        handles, labels = axes[0].get_legend_handles_labels()  # the target only: the colours are in axes[1]
        axes[0].legend([h for h, t in zip(handles, labels) if not t.startswith("lambda")],
                       [t for t in labels if not t.startswith("lambda")], fontsize=7, loc="lower left")
        axes[1].legend(fontsize=6, ncol=2)
        fig.suptitle("Adaptive ensemble: prefixes of every (xi, lambda) cell against the fast rule's half-width")
        paths.append(out_dir / "frontier_prefix.png")
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)
    return paths


def run(scenario: Scenario, data_dir: str | Path | None = None) -> dict[str, Any]:
    """All three sweeps; with ``data_dir``, save frontier.nc and the figures; JSON-ready summary."""
    contact_rows = contact_frontier(scenario)
    cube_rows = cube_frontier(scenario)
    ensemble = ensemble_frontier(scenario)
    result: dict[str, Any] = {"recommended": recommend(contact_rows, cube_rows, ensemble),
                              "contact": contact_rows, "cube": cube_rows}
    if data_dir is not None:
        prefix, note = adaptive_prefix(scenario, data_dir)
        result["prefix"] = prefix_summary(prefix, note)
        path = write(contact_rows, cube_rows, ensemble, Path(data_dir) / "bench" / "frontier.nc", prefix, note)
        with xr.open_dataset(path, decode_timedelta=False) as ds:
            plot(ds.load(), Path(data_dir) / "figures")
    return result
