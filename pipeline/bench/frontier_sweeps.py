"""The accuracy–time frontier's three sweeps: contact settings, cube settings and ensemble size.

Each is measured against a reference computed in the same process (see :mod:`g2tom.bench.frontier`,
which writes, plots and turns them into a recommendation).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable, TypeVar

import numpy as np
import xarray as xr

from g2tom.bench.schema import FRONTIER
from g2tom.bench.timing import median_time
from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario, Scenario
from g2tom.physics.radial_grid import force_weights
from g2tom.stages.schema import labelled

__all__ = ["contact_frontier", "cube_frontier", "ensemble_frontier", "NODES", "TOLERANCES", "METHODS", "CROPS"]

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


def _median_time(fn: Callable[[], Any], repeats: int | None = None) -> tuple[float, Any]:
    """Median wall time (s) of ``repeats`` (default :data:`REPEATS`) calls of ``fn`` and its result."""
    return median_time(fn, REPEATS if repeats is None else repeats)


#: A scenario's type, resolved or not: :func:`_replace` keeps it.
_S = TypeVar("_S", bound=Scenario)


def _replace(scenario: _S, section: str, **changes: Any) -> _S:
    return dataclasses.replace(scenario, **{section: dataclasses.replace(getattr(scenario, section), **changes)})


def _force_and_area(scenario: Scenario, r: np.ndarray, sols: list) -> tuple[np.ndarray, np.ndarray]:
    """Force (N) and real contact area (m^2) of every approach."""
    from g2tom.contact_solution import fields

    f = fields(scenario, r, sols)
    return f["force"], f["area"] @ force_weights(r)


def contact_frontier(scenario: Scenario) -> list[dict[str, Any]]:
    """Every contact setting with its time (s) and largest relative force and area errors."""
    from g2tom.before_work.domains import solve_scenario

    n_ref = 4 * scenario.contact.n_radial
    r, sols = solve_scenario(scenario, solver="newton", n_radial=n_ref, tolerance=1e-12)
    ref_force, ref_area = _force_and_area(scenario, r, sols)
    settings = [("newton", n, "graded", tol) for n in NODES for tol in TOLERANCES]
    settings += [("fixed_point", 20, "uniform", scenario.contact.fixed_point_tolerance),
                 ("fixed_point", scenario.contact.n_radial, "graded", scenario.contact.fixed_point_tolerance)]
    rows = []
    for solver, n, grid, tol in settings:
        s = _replace(scenario, "contact", radial_grid=grid)
        seconds, (r, sols) = _median_time(
            lambda s=s, n=n, tol=tol, solver=solver: solve_scenario(
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


def cube_frontier(scenario: ResolvedScenario) -> list[dict[str, Any]]:
    """Every (algorithm, crop tolerance, precision) with its time and errors in R, alpha, gamma."""
    from g2tom.stages import contact, cube, fits, oxide

    base = _replace(_replace(scenario, "oxide", **SUBSET, ensemble="fixed", n_realizations=CUBE_REALIZATIONS),
                    "fits", n_bootstrap=10)
    quiet = ComputeOptions(progress=False)
    contact_ds, oxide_ds = contact.build(base), oxide.build(base, quiet)

    def build(method: str, crop: float, spots: xr.Dataset) -> tuple[float, xr.Dataset, xr.Dataset]:
        s = _replace(_replace(base, "cube", crop_tolerance=crop), "compute", interaction_sum=method)
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


def ensemble_frontier(scenario: ResolvedScenario) -> xr.Dataset:
    """Interval widths of alpha and gamma and time against the number of realizations."""
    from g2tom.stages import contact, cube, fits, oxide

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
    ds = xr.Dataset(
        {
            "alpha_halfwidth": labelled(FRONTIER["alpha_halfwidth"], np.array(widths["alpha"])),
            "gamma_halfwidth": labelled(FRONTIER["gamma_halfwidth"], np.array(widths["gamma"])),
            "alpha": labelled(FRONTIER["alpha"], np.array(values["alpha"])),
            "gamma": labelled(FRONTIER["gamma"], np.array(values["gamma"])),
            "ensemble_seconds": labelled(FRONTIER["ensemble_seconds"], np.array(seconds)),
        },
        coords={
            "n_realizations": labelled(FRONTIER["n_realizations"], np.array(counts)),
            "xi": labelled(FRONTIER["xi"], np.array(base.oxide.xi)),
            "lambda": labelled(FRONTIER["lambda"], np.array(base.oxide.lambda_)),
        },
        attrs={"confidence": base.fits.confidence, "n_bootstrap": base.fits.n_bootstrap},
    )
    return ds
