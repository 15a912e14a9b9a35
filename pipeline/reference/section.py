"""The validation's report section (markdown); its figure is drawn by :mod:`g2tom.analysis.figures_validate`."""

from __future__ import annotations

import numpy as np
import xarray as xr

from g2tom.reference.discrete_spots import DISCRETE
from g2tom.reference.ensemble import MAX_ROUNDS, STAND_IN_TOLERANCE
from g2tom.reference.scene import capped_contact
from g2tom.reference.summary import ratios

__all__ = ["markdown", "CLEAN_LIMIT", "OXIDE_LIMIT", "MEANINGS"]

#: What each discretization is, for the section's legend.
MEANINGS = {
    "mean_area": "one spot per cell of the cell's mean contact area (the paper's)",
    "expected": "one spot per cell of the expected sum of asperity radii (Barber-consistent)",
    "asperities": "one asperity per cell, its height drawn per realization",
    "surface_asperities": "the GW surface's own asperities in g2tom's cells at Greenwood-Tripp's separation: "
                          "against the full field, what remains is Greenwood-Tripp's averaging and the "
                          "resistance model",
    DISCRETE: "the discrete model on the GW surface's own asperities: the caps coupled through the half-space "
                "at g2tom's forces, oxide counted per spot (the validated scenario's rule: disc or segment); against "
                "the full field it measures the "
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
    """Part 1's first lines: where the default's discretization and model miss the limits, with numbers."""
    spots, model = ds.attrs["default_discretization"], ds.attrs["default_model"]
    if spots not in ds["discretization"].values or model not in ds["model"].values:
        return []  # e.g. the discrete model on the random-process surface, whose asperities are not known
    if f"{spots}/{model}:" in ds.attrs.get("skipped_g2tom", "none"):
        return []
    f = ds["force"].values
    lines = []
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
        lines.append(f"g2tom's default discretization ({spots}, {model}) is within ±{100 * CLEAN_LIMIT:.0f} % of "
                     f"the full field clean and ±{100 * OXIDE_LIMIT:.0f} % oxidized at every load, surface by surface.")
    return lines


def _ensemble_cells(ds: xr.Dataset) -> list[tuple[str, dict]]:
    """Part 2's cases: (label, selection) for clean (empty selection) and every xi x lambda."""
    return [("clean", {})] + [(f"xi {x:g}, lambda {lam:g}", {"xi": x, "lambda": lam})
                              for x in ds["xi"].values for lam in ds["lambda"].values]


def _at(ds: xr.Dataset, name: str, sel: dict, k: int, suffix: str = "") -> float:
    """Part 2's variable ``name`` (``name_clean`` for the clean case, an empty ``sel``) with
    ``suffix`` (e.g. ``_standard_error``) at load ``k``."""
    var = ds[f"{name}{suffix}"].sel(sel) if sel else ds[f"{name}_clean{suffix}"]
    return float(var.isel(load=k))


def _ensemble_flags(ds: xr.Dataset) -> list[str]:
    """Part 2's first lines: where the validated scenario's ensemble is outside the accuracy targets, and
    where a standard error misses the set's (both with numbers)."""
    if "ensemble_ratio" not in ds:
        return []
    f = ds["force_normalized"].values
    outside, loose = [], []
    for label, sel in _ensemble_cells(ds):
        goal = ds.attrs["scene_clean_error"] if not sel else ds.attrs["scene_oxide_error"]
        for k in range(ds.sizes["load"]):
            r, t = _at(ds, "ensemble_ratio", sel, k), _at(ds, "ensemble_target", sel, k)
            se = _at(ds, "ensemble_ratio", sel, k, "_standard_error")
            if np.isfinite(t) and not abs(r - 1.0) <= t:
                outside.append(f"{label} {100 * (r - 1):+.1f} ± {100 * se:.1f} % at F' {f[k]:.3g} (target "
                               f"{100 * t:.0f} %)")
            if not se <= goal:
                pairs = _pairs_error(ds, sel, k)
                loose.append(f"{label} at F' {f[k]:.3g}: {se:.3f} > {goal:g}"
                             + (f" (the pairs alone {pairs:.3f})" if np.isfinite(pairs) else ""))
    name = ds.attrs.get("validated_scenario", "the default")
    lines = []
    if outside:
        lines.append(f"**Part 2: the ensemble of {name} is outside the accuracy targets against the full field's in "
                     f"{len(outside)} (case, load) pairs: " + "; ".join(outside) + ".**")
    else:
        lines.append(f"Part 2: the ensemble of {name} is within the accuracy targets against the full field's at every "
                     "load and case that has one.")
    if loose:
        lines.append(f"Part 2's standard error of ln ratio misses the set's ({ds.attrs['scene_clean_error']:g} clean, "
                     f"{ds.attrs['scene_oxide_error']:g} oxidized) in {len(loose)} (case, load) pairs (more "
                     f"realizations than the set's max_ensemble {ds.attrs['scene_max_ensemble']} allows, or the "
                     "pairs' own scatter, sd(ln main grid / proxy) / sqrt(P), which no count of proxies lowers, at "
                     f"the set's max_pairs {ds.attrs.get('scene_max_pairs', 'P')}, or the sizing's estimate of the "
                     f"scatter after {MAX_ROUNDS} rounds): "
                     + "; ".join(loose) + ".")
    return lines


def _pairs_error(ds: xr.Dataset, sel: dict, k: int) -> float:
    """The pairs' share of the full field's standard error at load ``k`` (NaN: none, or a file
    written before it was recorded)."""
    name = "ensemble_reference_pairs_standard_error" if sel else "ensemble_reference_clean_pairs_standard_error"
    return float(ds[name].sel(sel).isel(load=k)) if name in ds else np.nan


def _ensemble_table(ds: xr.Dataset) -> list[str]:
    """Part 2's table and its notes (stand-in, ensemble grid)."""
    if "ensemble_ratio" not in ds:
        return []
    cells = _ensemble_cells(ds)
    lines = [f"### Part 2: the default's ensemble ({ds.attrs.get('validated_model', '')})", "",
             f"The validated scenario's ensemble (clean: {int(ds['ensemble_model_count_clean'])} "
             + ("value, one exact answer" if int(ds["ensemble_model_count_clean"]) == 1 else "surfaces")
             + f"; oxidized: {int(ds['ensemble_model_count'])} realizations) against the full field's, each as the geometric mean of R over its conducting realizations at equal force; ratio ± the "
             "standard error of its log (both ensembles', in squares); ✓ within the accuracy target at that F', ✗ outside, "
             "no mark where the accuracy target sets none (oxidized below F' 1). The full field's ensemble: N realizations, a "
             "proxy on all N corrected by P paired main-grid solves (two-phase: part 1's realizations, then more "
             "where the proxy and the full field disagree, sized with the proxies at least cost; N = P: the pairs "
             "alone). Open circuits (R = +inf) are counted, full field / model, where any.", "",
             "| F (N) | F' | N full field (P pairs) | " + " | ".join(label for label, _ in cells) + " |",
             "|---|---|---|" + "---|" * len(cells)]
    for k in range(ds.sizes["load"]):
        row = []
        for _, sel in cells:
            r, t = _at(ds, "ensemble_ratio", sel, k), _at(ds, "ensemble_target", sel, k)
            se = _at(ds, "ensemble_ratio", sel, k, "_standard_error")
            mark = "" if not np.isfinite(t) else (" ✓" if abs(r - 1.0) <= t else " ✗")
            text = "no ratio" if not np.isfinite(r) else f"{r:.3f} ± {se:.3f}{mark}"
            if sel:
                ref_open = float(ds["ensemble_reference_open_fraction"].sel(sel).isel(load=k))
                mod_open = float(ds["ensemble_model_open_fraction"].sel(sel).isel(load=k))
                if ref_open > 0 or mod_open > 0:
                    text += f" (open {100 * ref_open:.0f} / {100 * mod_open:.0f} %)"
            row.append(text)
        counts = sorted({int(_at(ds, "ensemble_count", sel, k)) for _, sel in cells})
        pairs = f" ({int(ds['ensemble_pairs'].values[k])})" if "ensemble_pairs" in ds else ""
        lines.append(f"| {ds['force'].values[k]:.4g} | {ds['force_normalized'].values[k]:.3g} | "
                     f"{'/'.join(map(str, counts))}{pairs} | " + " | ".join(row) + " |")
    lines.append("")
    lines += _stand_in_notes(ds) + _grid_notes(ds)
    return lines


def _stand_in_notes(ds: xr.Dataset) -> list[str]:
    """Where the discrete solve stood in for the full field, with part 1's numbers beside it."""
    if DISCRETE not in ds["discretization"].values or "point" not in ds["model"].values:
        return []
    used = []
    f = ds["force_normalized"].values
    part1 = ds.sel(discretization=DISCRETE, model="point")
    for label, sel in _ensemble_cells(ds):
        flag = ds["ensemble_stand_in_clean"] if not sel else ds["ensemble_stand_in"].sel(sel)
        ratio = part1["ratio_clean"] if not sel else part1["ratio"].sel(sel)
        for k in np.flatnonzero(flag.values):
            gm, lo, hi, _ = ratios(ratio.isel(load=k).values[:, None])
            used.append(f"{label} at F' {f[k]:.3g} (part 1: {gm[0]:.3f} [{lo[0]:.3f}-{hi[0]:.3f}])")
    if not used:
        return [f"No stand-in: the discrete solve of each surface's own caps was not within "
                f"{100 * STAND_IN_TOLERANCE:g} % of the full field at every part-1 realization of any (case, load), "
                "or the surface's asperities are not known.", ""]
    return [f"Stand-in: where part 1 shows the discrete solve of each surface's own caps (point model) within "
            f"{100 * STAND_IN_TOLERANCE:g} % of the full field at every realization, that solve is the full field's "
            "proxy for the extra realizations (corrected by the pairs): " + "; ".join(used) + ".", ""]


def _grid_notes(ds: xr.Dataset) -> list[str]:
    """The ensemble grid against the main grid on the pairs' realizations (clean), where it was used."""
    check = ds["ensemble_grid_check_clean"].values
    f = ds["force_normalized"].values
    used = np.flatnonzero(np.isfinite(check))
    if not used.size:
        return []
    return [f"Ensemble grid ({ds.attrs['scene_ensemble_grid']}^2) against the main grid ({ds.attrs['scene_n_grid']}^2), "
            "clean, geometric mean over the pairs' realizations (the two-phase estimate removes this offset): "
            + ", ".join(f"{check[k]:.4f} at F' {f[k]:.3g}" for k in used) + ".", ""]


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
    lines += _flags(ds) + _ensemble_flags(ds) + _isolation(ds)
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
        f"{n_real} realization(s); the reference is solved at g2tom's force"
        + ("" if "scene_hardness" not in ds.attrs else f", its {capped_contact(ds.attrs['scene_hardness'])}")
        + ". Ratio g2tom / full field: geometric mean ± the standard error of its log (paired over realizations) "
        "[min-max].", "",
    ]
    lines += _ensemble_table(ds)
    lines += ["### Part 1: exactness per surface (paired)", "",
              "Discretizations: " + "; ".join(f"{d}: {MEANINGS.get(str(d), 'no description')}"
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
              "conductance / (K / (E* rho*)) = " + ", ".join(f"{b:.4f}" for b in ds["barber_ratio"].values)
              + ("." if "scene_hardness" not in ds.attrs else
                 ", K the unloading stiffness (the heights flattened where the pressure is at H, pressed elastically; "
                 "the loading slope dF/d(-delta) is lower where the caps yield)."),
              f"Wall time: {float(np.nansum(ds['seconds_case'].values)):.0f} s for the main grid's cases "
              f"(contact solves {float(np.nansum(ds['seconds_contact'].values)):.0f} s; CPU "
              f"{float(np.nansum(ds['seconds_cpu_case'].values)):.0f} s), "
              f"{float(np.nansum(ds['seconds_convergence'].values)):.0f} s for the convergence grid"
              + (f", {float(np.nansum(ds['ensemble_seconds'].values)):.0f} s for part 2's cases (CPU "
                 f"{float(np.nansum(ds['ensemble_seconds_cpu'].values)):.0f} s)" if "ensemble_seconds" in ds else "")
              + " (summed over the workers).", ""]
    return "\n".join(lines)
