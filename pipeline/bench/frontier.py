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
  (xi, lambda), the fast rule's half-widths of alpha and gamma (:func:`g2tom.stages.cube_rounds.half_widths`)
  at log-spaced prefixes n = 50 .. the cell's count, and the cube time prorated to n.

``make bench`` writes ``<data_dir>/bench/frontier.nc`` (:func:`write`) and its figures
``frontier_contact.png``, ``frontier_cube.png``, ``frontier_ensemble.png`` (and
``frontier_prefix.png`` with a prefix curve) under ``<data_dir>/figures``; :func:`recommend` turns the sweeps into a setting per use.
"""


from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.bench.frontier_plot import plot
from g2tom.bench.frontier_prefix import adaptive_prefix, prefix_summary
from g2tom.bench.frontier_sweeps import contact_frontier, cube_frontier, ensemble_frontier
from g2tom.bench.schema import sweep_column, sweep_index
from g2tom.config import ResolvedScenario
from g2tom.stages.schema import labelled
from g2tom.store import atomic_path

__all__ = ["run", "recommend", "write", "USES"]

#: Uses and their targets: contact force error, cube R error, relative interval half-width.
USES: dict[str, dict[str, float]] = {
    "quick look": {"force_error": 1e-3, "resistance_error": 1e-3, "interval": 0.10},
    "paper-grade": {"force_error": 1e-5, "resistance_error": 1e-5, "interval": 0.05},
    "publication-grade": {"force_error": 1e-7, "resistance_error": 1e-8, "interval": 0.025},
}


def _table(rows: list[dict[str, Any]], dim: str) -> xr.Dataset:
    """Rows of equal keys as a dataset over ``dim`` (strings stay strings)."""
    data = {}
    for key in rows[0]:
        values = np.array([r[key] for r in rows])
        if values.dtype == bool:
            values = values.astype(np.int8)
        data[f"{dim}_{key}"] = labelled(sweep_column(dim, key), values)
    return xr.Dataset(data, coords={dim: labelled(sweep_index(dim), np.arange(len(rows)))})


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
            "cube": f"interaction_sum={k['method']} crop_tolerance={k['crop_tolerance']:g}",
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


def run(scenario: ResolvedScenario, data_dir: str | Path | None = None) -> dict[str, Any]:
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
