"""Convergence of alpha and gamma in the oxide field's spectral resolution, and field cost.

Runs the cube and the fits twice on the scenario's grid, at ``oxide.spectral_resolution`` r and
at 2 r (period "spectral", the scenario's ensemble rule with the cap lowered to at most
:data:`CAP` realizations to keep the benchmark short), and once with the window as the period
(the published lattice) as a control. Fields at two resolutions are different random fields
(other modes, other phases), so the change of a fitted value is compared with the half-width of
the difference, ``sqrt(hw_r^2 + hw_2r^2)`` (95 %), and also with the finer run's own half-width.
Converged means: no cell's change exceeds the combined half-width beyond the ~5 % of cells
expected by chance, while the window control shows where the lattice moves the numbers.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario
from g2tom.stages import contact, cube, fits, oxide

__all__ = ["run", "compare", "fit_at"]

#: Largest ensemble per cell in each run of the benchmark.
CAP = 4000


def fit_at(scenario: ResolvedScenario, contact_ds: xr.Dataset, options: ComputeOptions) -> tuple[xr.Dataset, float]:
    """Cube and fits of ``scenario`` on a given contact; returns fits.nc's dataset and the seconds."""
    start = time.perf_counter()
    record = oxide.build(scenario, options)
    ds = fits.build(scenario, cube.build(scenario, contact_ds, record, options))
    return ds, time.perf_counter() - start


def compare(coarse: xr.Dataset, fine: xr.Dataset) -> dict[str, Any]:
    """Changes of alpha (relative) and gamma (absolute) against their half-widths, per cell.

    Returns
    -------
    dict
        ``rows`` (one per cell), the largest ratios and the counts of cells whose change
        exceeds the combined half-width and the finer run's half-width.
    """
    d_alpha = np.abs(fine["alpha"] / coarse["alpha"] - 1.0)
    d_gamma = np.abs(fine["gamma"] - coarse["gamma"])
    hw = {k: (coarse[f"{k}_half_width"], fine[f"{k}_half_width"]) for k in ("alpha", "gamma")}
    both = {k: np.sqrt(a**2 + b**2) for k, (a, b) in hw.items()}
    rows = []
    for xi in fine["xi"].values:
        for lam in fine["lambda"].values:
            cell = {"xi": xi, "lambda": lam}
            rows.append({
                "xi": float(xi), "lambda": float(lam),
                "alpha_coarse": float(coarse["alpha"].sel(cell)), "alpha_fine": float(fine["alpha"].sel(cell)),
                "alpha_change": float(d_alpha.sel(cell)), "alpha_half_width_combined": float(both["alpha"].sel(cell)),
                "gamma_coarse": float(coarse["gamma"].sel(cell)), "gamma_fine": float(fine["gamma"].sel(cell)),
                "gamma_change": float(d_gamma.sel(cell)), "gamma_half_width_combined": float(both["gamma"].sel(cell)),
                "n_fine": int(fine["n_realizations"].sel(cell)),
            })
    return {
        "cells": int(d_alpha.size),
        "alpha_max_change_over_combined": float((d_alpha / both["alpha"]).max()),
        "gamma_max_change_over_combined": float((d_gamma / both["gamma"]).max()),
        "alpha_cells_over_combined": int((d_alpha > both["alpha"]).sum()),
        "gamma_cells_over_combined": int((d_gamma > both["gamma"]).sum()),
        "alpha_cells_over_fine_half_width": int((d_alpha > hw["alpha"][1]).sum()),
        "gamma_cells_over_fine_half_width": int((d_gamma > hw["gamma"][1]).sum()),
        "rows": rows,
    }


def _table(result: dict[str, Any]) -> str:
    """The per-cell comparison as a text table."""
    lines = [f"{'xi':>4} {'lam':>4} {'alpha r':>8} {'alpha 2r':>8} {'|d|/a %':>7} {'hw %':>6} "
             f"{'gamma r':>7} {'gamma 2r':>8} {'|d|':>6} {'hw':>6} {'n':>6}"]
    for r in result["rows"]:
        lines.append(
            f"{r['xi']:4.1f} {r['lambda']:4.0f} {r['alpha_coarse']:8.4f} {r['alpha_fine']:8.4f} "
            f"{100 * r['alpha_change']:7.2f} {100 * r['alpha_half_width_combined']:6.2f} "
            f"{r['gamma_coarse']:7.4f} {r['gamma_fine']:8.4f} {r['gamma_change']:6.4f} "
            f"{r['gamma_half_width_combined']:6.4f} {r['n_fine']:6d}"
        )
    return "\n".join(lines)


def run(scenario: ResolvedScenario) -> dict[str, Any]:
    """Resolution r against 2 r, and the window period against r, on the scenario's grid.

    Returns
    -------
    dict
        ``resolution`` (r), ``doubling`` and ``window_control`` (see :func:`compare`, rows
        dropped from the JSON summary lines but kept in the file), the wall seconds of each run
        and the field cost per field at r and 2 r (:mod:`g2tom.bench.oxide` reports more).
    """
    ox = scenario.oxide
    options = ComputeOptions(progress=False)
    base = dataclasses.replace(scenario, oxide=dataclasses.replace(
        ox, period="spectral", max_realizations=min(ox.max_realizations, CAP),
        min_realizations=min(ox.min_realizations, CAP)))
    contact_ds = contact.build(base)
    runs: dict[str, tuple[xr.Dataset, float]] = {}
    for label, changes in (
        ("r", {}),
        ("2r", {"spectral_resolution": 2.0 * ox.spectral_resolution}),
        ("window", {"period": "window"}),
    ):
        variant = dataclasses.replace(base, oxide=dataclasses.replace(base.oxide, **changes))
        runs[label] = fit_at(variant, contact_ds, options)
    doubling = compare(runs["r"][0], runs["2r"][0])
    control = compare(runs["r"][0], runs["window"][0])
    print(_table(doubling))
    return {
        "resolution": ox.spectral_resolution,
        "cap": CAP,
        "seconds": {k: v[1] for k, v in runs.items()},
        "doubling": doubling,
        "window_control": {k: v for k, v in control.items() if k != "rows"},
    }
