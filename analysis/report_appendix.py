"""Report appendix sections: the accuracy–time frontier, the stability map, the benchmark records, the
parameters and the timings."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.analysis.report_blocks import Block, table as _table
from g2tom.config import Scenario, parameter_table

__all__ = ["FRONTIER_FIGURES", "frontier_blocks", "stability_blocks", "benchmark_blocks", "parameter_blocks",
           "timing_blocks"]


#: Figures of the frontier benchmark, shown in "How fast, how accurate".
FRONTIER_FIGURES = {
    "frontier_contact": "Contact: error of the force and of the real contact area against solve time, per "
                        "tolerance (labels: radial nodes), and the paper's relaxed fixed point",
    "frontier_cube": "Cube: error of R, alpha and gamma against cube time per algorithm and crop tolerance, "
                     "and the spot maps rounded to float32",
    "frontier_ensemble": "Ensemble: relative half-width of the alpha and gamma intervals against the number of "
                         "realizations per (xi, lambda), time on the top axis",
}


def frontier_blocks(data_dir: Path) -> list[Block]:
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


def stability_blocks(data_dir: Path) -> list[Block]:
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


def _size(n_bytes: int) -> str:
    """A file size as text: bytes below 1 kB, else kB or MB with one decimal."""
    if n_bytes < 1000:
        return f"{n_bytes} B"
    return f"{n_bytes / 1e3:.1f} kB" if n_bytes < 1e6 else f"{n_bytes / 1e6:.1f} MB"


def benchmark_blocks(data_dir: Path) -> list[Block]:
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


def timing_blocks(scenario: Scenario, data_dir: Path, report_seconds: float) -> list[Block]:
    """Wall times of the runs that made the files this report describes, figures and report too.

    ``timings.json`` keeps the last time of every step with the configuration hash it ran
    with; steps run with another configuration (an earlier or a different run) are left out.
    """
    from g2tom.analysis.report_summary import TIMED_STEPS, recorded_timings

    blocks = [Block("h2", "Timings")]
    rows = [list(row) for row in recorded_timings(scenario, data_dir)]
    rows.append(["report", round(report_seconds, 3), "(this page)"])
    rows.append(["total", round(sum(r[1] for r in rows), 3), ""])
    blocks.append(_table(["step", "wall time (s)", "finished (UTC)"], rows))
    left_out = [step for step in TIMED_STEPS if step not in {r[0] for r in rows}]
    if left_out:
        blocks.append(Block("p", "No time of this configuration's run for: " + ", ".join(left_out)
                            + " (run through another configuration, or not through the g2tom command)."))
    return blocks


def parameter_blocks(scenario: Scenario) -> list[Block]:
    """Section "Parameters": every parameter of the scenario with its value, unit and meaning."""
    values = scenario.flat()
    return [Block("h2", "Parameters"), _table(
        ["parameter", "value", "unit", "meaning"],
        [[key, values[key], unit, doc] for key, _default, unit, _allowed, doc in parameter_table()],
    )]
