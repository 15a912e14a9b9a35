"""The validation's report section (markdown); its figure is drawn by :mod:`analysis.figures_validate`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.reference.summary import ratios
from pipeline.store import atomic_path

__all__ = ["markdown", "CLEAN_LIMIT", "OXIDE_LIMIT", "MEANINGS"]

#: What each discretization is, for the section's legend.
MEANINGS = {
    "mean_area": "one spot per cell of the cell's mean contact area (the paper's)",
    "expected": "one spot per cell of the expected sum of asperity radii (Barber-consistent; the default)",
    "asperities": "one asperity per cell, its height drawn per realization",
    "surface_asperities": "the GW surface's own asperities in g2tom's cells at Greenwood-Tripp's separation: "
                          "against the full field, what remains is Greenwood-Tripp's averaging and the "
                          "resistance model",
    "discrete": "the discrete model on the GW surface's own asperities: the caps coupled through the half-space "
                "at g2tom's forces, oxide counted per spot (disc rule); against the full field it measures the "
                "discrete model itself",
}
#: Relative deviations of the default discretization that the section's first lines flag.
CLEAN_LIMIT = 0.10
OXIDE_LIMIT = 0.20


def _cell(gm: float, lo: float, hi: float, count: int, total: int, error: float = np.nan) -> str:
    if count == 0:
        return "open"
    open_note = f", {total - count} open" if count < total else ""
    spread = f" ± {error:.3f}" if np.isfinite(error) else ""
    return f"{gm:.3f}{spread} [{lo:.3f}-{hi:.3f}{open_note}]"


def _flags(ds: xr.Dataset) -> list[str]:
    """The section's first lines: where the default discretization misses the limits, with numbers."""
    spots = ds.attrs["default_discretization"]
    f = ds["force"].values
    lines = []
    for model in ds["model"].values:
        if f"{spots}/{model}:" in ds.attrs.get("skipped_g2tom", "none"):
            continue
        clean = ratios(ds["ratio_clean"].sel(discretization=spots, model=model).values)[0]
        bad = np.flatnonzero(~(np.abs(clean - 1.0) <= CLEAN_LIMIT))
        if bad.size:
            where = ", ".join(f"{100 * (clean[k] - 1):+.1f} % at {f[k]:.4g} N" for k in bad)
            lines.append(f"**Clean: g2tom's default discretization ({spots}, {model}) is off the full field by "
                         f"more than ±{100 * CLEAN_LIMIT:.0f} %: {where}.**")
        ox = ratios(ds["ratio"].sel(discretization=spots, model=model).values)[0]  # (xi, lambda, load)
        bad = np.argwhere(~(np.abs(ox - 1.0) <= OXIDE_LIMIT))
        if len(bad):
            z, a, k = max(bad, key=lambda i: abs(np.log(ox[tuple(i)])) if np.isfinite(ox[tuple(i)]) else np.inf)
            lines.append(f"**Oxidized: g2tom's default discretization ({spots}, {model}) is off the full field by "
                         f"more than ±{100 * OXIDE_LIMIT:.0f} % in {len(bad)} of {ox.size} (case, load) pairs; worst "
                         f"{100 * (ox[z, a, k] - 1):+.1f} % at xi {ds['xi'].values[z]:g}, lambda "
                         f"{ds['lambda'].values[a]:g}, {f[k]:.4g} N.**")
    if not lines:
        lines.append(f"g2tom's default discretization ({spots}) is within ±{100 * CLEAN_LIMIT:.0f} % of the full "
                     f"field clean and ±{100 * OXIDE_LIMIT:.0f} % oxidized at every load.")
    return lines


def _pixels(ds: xr.Dataset) -> str:
    """The main grid's pixel sizes over the cases, and per asperity spacing."""
    pixel = ds["window_side"].values / ds.attrs["scene_n_grid"]
    spacing = 1.0 / np.sqrt(ds.attrs["scene_eta"])
    if not np.isfinite(pixel).any():
        return "no case solved"
    lo, hi = np.nanmin(pixel), np.nanmax(pixel)
    return (f"pixels {lo * 1e6:.3g}-{hi * 1e6:.3g} um, {spacing / hi:.3g}-{spacing / lo:.3g} per asperity spacing; "
            f"windows {np.nanmin(ds['window_side'].values) * 1e3:.3g}-{np.nanmax(ds['window_side'].values) * 1e3:.3g} mm")


def _isolation(ds: xr.Dataset) -> list[str]:
    """What the surface's own asperities leave of the clean error (Greenwood-Tripp's averaging and the
    model), beside the default discretization's, per model: geometric means and open circuits."""
    own, spots = "surface_asperities", ds.attrs["default_discretization"]
    if own not in ds["discretization"].values or spots not in ds["discretization"].values:
        return []
    total = ds.sizes["realization"]
    lines = []
    for model in ds["model"].values:
        parts = []
        for d in (own, spots):
            gm, _, _, count = ratios(ds["ratio_clean"].sel(discretization=d, model=model).values)
            parts.append(", ".join(f"{g:.3f}" + (f" ({total - c} of {total} open)" if c < total else "")
                                   for g, c in zip(gm, count)))
        lines.append(f"Clean, {model}: on each surface's own asperities g2tom / full field = {parts[0]} at the loads "
                     f"(what Greenwood-Tripp's averaging and the model leave); {spots}: {parts[1]}.")
    return lines


def markdown(ds: xr.Dataset) -> str:
    """The report section: flags first, then the ratio tables, the grid convergence and the wall times."""
    n_real = ds.sizes["realization"]
    lines = ["## How right is the model? g2tom against the full-field reference", ""]
    lines += _flags(ds) + _isolation(ds)
    if ds.attrs.get("failed_cases", "none") != "none":
        lines.append(f"**Failed reference cases (NaN in the tables): {ds.attrs['failed_cases']}.**")
    lines.append("")
    lines += [
        f"Scene: mu = {ds.attrs['mu']:.3f}, sigma {ds.attrs['scene_sigma']:g} m, eta {ds.attrs['scene_eta']:g} m^-2, "
        f"beta {ds.attrs['scene_beta']:g} m, R* {ds.attrs['scene_radius']:g} m; "
        + ("GW surfaces" if ds.attrs.get("scene_surface", "gw") == "gw" else
           f"Gaussian self-affine surfaces (H {ds.attrs['scene_hurst']:g}, rms {ds.attrs['scene_rms']:g} m; g2tom fed "
           "their summit statistics)") + " on a "
        f"{ds.attrs['scene_n_grid']}^2 grid on each case's window, fitted to its contact ({_pixels(ds)}), "
        f"{n_real} realization(s); the reference is solved at g2tom's force. Ratio g2tom / full field: "
        "geometric mean ± the standard error of its log (paired over realizations) [min-max].", "",
    ]
    lines += ["Discretizations: " + "; ".join(f"{d}: {MEANINGS.get(str(d), 'no description')}"
                                          for d in ds["discretization"].values) + ".", ""]
    skipped = ds.attrs.get("skipped_g2tom", "none")
    if skipped != "none":
        lines += [f"Not compared (g2tom refuses the combination): {skipped}", ""]
    cases = ["clean"] + [f"xi {x:g}, lambda {lam:g}" for x in ds["xi"].values for lam in ds["lambda"].values]
    for d in ds["discretization"].values:
        for m in ds["model"].values:
            if f"{d}/{m}:" in skipped:
                continue
            lines += [f"### {d}, {m}", "", "| F (N) | F' | " + " | ".join(cases) + " |",
                      "|---|---|" + "---|" * len(cases)]
            clean = ratios(ds["ratio_clean"].sel(discretization=d, model=m).values)
            ox = ratios(ds["ratio"].sel(discretization=d, model=m).values)
            se_clean = ds["ratio_clean_standard_error"].sel(discretization=d, model=m).values
            se_ox = ds["ratio_standard_error"].sel(discretization=d, model=m).values
            for k in range(ds.sizes["load"]):
                row = [_cell(*(v[k] for v in clean), n_real, se_clean[k])]
                row += [_cell(*(v[z, a, k] for v in ox), n_real, se_ox[z, a, k])
                        for z in range(ds.sizes["xi"]) for a in range(ds.sizes["lambda"])]
                lines.append(f"| {ds['force'].values[k]:.4g} | {ds['force_normalized'].values[k]:.3g} | "
                             + " | ".join(row) + " |")
            lines.append("")
    change = ds["convergence_change"].values
    lines += [f"Grid convergence (first realization, clean): doubling the grid step ({ds['grid'].values[0]}^2 -> "
              f"{ds['grid'].values[1]}^2) changes R by " + ", ".join(f"{100 * c:+.2f} %" for c in change) + " at the loads.",
              "Barber's theorem on the full-field clean solution (convergence grid, first realization): punch "
              "conductance / (K / (E* rho*)) = " + ", ".join(f"{b:.4f}" for b in ds["barber_ratio"].values) + ".",
              f"Wall time: {float(np.nansum(ds['seconds_case'].values)):.0f} s for the main grid's cases "
              f"(contact solves {float(np.nansum(ds['seconds_contact'].values)):.0f} s), "
              f"{float(np.nansum(ds['seconds_convergence'].values)):.0f} s for the convergence grid.", ""]
    return "\n".join(lines)
