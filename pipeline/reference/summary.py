"""The validation's labelled dataset (validate.nc) and the ratio statistics of the report.

Ratios are g2tom / full field at equal force, per realization; the report gives their geometric
mean and range over the realizations where both resistances are finite (an open circuit, R = +inf,
is counted, not averaged).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import xarray as xr

from pipeline import __version__
from pipeline.fitting.ensemble import log_standard_error
from pipeline.reference import scene
from pipeline.store import git_commit

__all__ = ["dataset", "ratios"]


def _a(units: str, long_name: str, **extra: Any) -> dict[str, Any]:
    return {"units": units, "long_name": long_name, **extra}


def _reference(vset: scene.ValidationSet, everything: list, done: dict) -> dict[str, np.ndarray]:
    """The main grid's records as arrays (realization, load) and (xi, lambda, realization, load)."""
    shape = (len(vset.realizations), len(vset.deltas))
    out = {k: np.full(shape, np.nan) for k in ("force", "delta", "contact_area", "resistance_clean", "side",
                                                "seconds_contact", "seconds_total")}
    out["resistance"] = np.full((len(vset.xi), len(vset.lambdas)) + shape, np.nan)
    coarse = {k: np.full(len(vset.deltas), np.nan) for k in ("resistance_clean", "seconds_total", "barber_ratio", "side")}
    out["failed"] = [f"{case.name}: {done[case]['error']}" for case in everything if "error" in done[case]]
    for case in everything:
        rec = done[case]
        if case.n != vset.n_grid:
            for k in coarse:
                coarse[k][case.load] = rec.get(k, np.nan)
            continue
        i = vset.realizations.index(case.realization)
        for k in ("force", "delta", "contact_area", "resistance_clean", "side", "seconds_contact", "seconds_total"):
            out[k][i, case.load] = rec.get(k, np.nan)
        out["resistance"][:, :, i, case.load] = np.asarray(rec["resistance"], float)
    out["coarse"] = coarse
    return out


def dataset(vset: scene.ValidationSet, everything: list, done: dict, g2tom: dict[str, np.ndarray],
            default_spots: str) -> xr.Dataset:
    """validate.nc: the reference and g2tom per realization and load, ratios, convergence, wall times."""
    ref = _reference(vset, everything, done)
    scale_r = 2.0 * vset.rho / np.sqrt(vset.radius * vset.sigma)
    scale_f = vset.e_star * np.sqrt(vset.radius * vset.sigma**3) / 2.0
    rl, ox = ("realization", "load"), ("xi", "lambda", "realization", "load")
    dm = ("discretization", "model")
    coords = {
        "load": ("load", np.arange(len(vset.deltas)), _a("1", "load step index, lightest first")),
        "realization": ("realization", np.asarray(vset.realizations), _a("1", "surface and oxide realization index")),
        "xi": ("xi", np.asarray(vset.xi, float), _a("1", "nominal oxide fraction")),
        "lambda": ("lambda", np.asarray(vset.lambdas, float), _a("1", "normalized oxide correlation length l_O sqrt(eta)")),
        "discretization": ("discretization", np.asarray(vset.discretizations), _a("1", "g2tom spot discretization (contact.spots)")),
        "model": ("model", np.asarray(vset.models), _a("1", "g2tom resistance model (cube.model)")),
        "grid": ("grid", np.array([vset.n_grid, vset.convergence_grid or vset.n_grid]),
                 _a("1", "pixels along one side of the reference grid (same window)")),
        "force": ("load", g2tom["force"], _a("N", "normal force F (g2tom's at its approach; the reference is solved at it)")),
        "force_normalized": ("load", g2tom["force"] / scale_f, _a("1", "normalized force F' = 2F / (E* sqrt(R* sigma^3))")),
        "delta_g2tom": ("load", np.asarray(vset.deltas) * vset.sigma, _a("m", "g2tom's approach delta at the force")),
    }
    with np.errstate(invalid="ignore"):  # both open circuits (inf / inf): no ratio, NaN
        clean_ratio = g2tom["clean"] / ref["resistance_clean"][None, None]
        ox_ratio = g2tom["resistance"] / ref["resistance"][None, None]
    fine = ref["resistance_clean"][0]
    data = {
        "force_reference": (rl, ref["force"], _a("N", "normal force of the full-field solution")),
        "delta_reference": (rl, ref["delta"], _a("m", "approach delta of the full-field solution (g2tom's convention)")),
        "contact_area": (rl, ref["contact_area"], _a("m2", "contact area of the full-field solution")),
        "window_side": (rl, ref["side"], _a("m", "side of the case's window (fitted to its contact)")),
        "window_side_convergence": ("load", ref["coarse"]["side"], _a("m", "side of the convergence case's window")),
        "resistance_reference_clean": (rl, ref["resistance_clean"], _a("ohm", "full-field clean resistance (Barber's analogy)")),
        "resistance_reference": (ox, ref["resistance"], _a("ohm", "full-field resistance with the oxide removed from the contact set",
                                                           comment="+inf: open circuit")),
        "resistance_g2tom_clean": (dm + rl, g2tom["clean"], _a("ohm", "g2tom's clean resistance (one value over the "
                                                               "realizations unless the spots are the surface's own)")),
        "resistance_g2tom": (dm + ox, g2tom["resistance"], _a("ohm", "g2tom's resistance on the same oxide field",
                                                             comment="+inf: open circuit")),
        "ratio_clean": (dm + rl, clean_ratio, _a("1", "g2tom / full-field clean resistance at equal force")),
        "ratio": (dm + ox, ox_ratio, _a("1", "g2tom / full-field oxidized resistance at equal force",
                                          comment="+inf: only g2tom open; 0: only the full field open; NaN: both")),
        "ratio_clean_standard_error": (dm + ("load",), log_standard_error(clean_ratio, axis=-2), _a(
            "1", "standard error of ln of the geometric-mean clean ratio over the realizations (paired)",
            comment="NaN with fewer than two finite ratios")),
        "ratio_standard_error": (dm + ("xi", "lambda", "load"), log_standard_error(ox_ratio, axis=-2), _a(
            "1", "standard error of ln of the geometric-mean oxidized ratio over the realizations (paired)",
            comment="NaN with fewer than two finite ratios")),
        "resistance_convergence": (("grid", "load"), np.stack([fine, ref["coarse"]["resistance_clean"]]),
                                   _a("ohm", "clean full-field resistance of the first realization on each grid")),
        "convergence_change": ("load", ref["coarse"]["resistance_clean"] / fine - 1.0,
                               _a("1", "relative change of the clean R when the grid step doubles")),
        "barber_ratio": ("load", ref["coarse"]["barber_ratio"], _a(
            "1", "punch conductance / (K / (E* rho*)), K = dF/d(-delta) from loads F (1 +- 1 %), convergence grid")),
        "seconds_contact": (rl, ref["seconds_contact"], _a("s", "wall time of the full-field contact solve")),
        "seconds_case": (rl, ref["seconds_total"], _a("s", "wall time of the case (contact and every conductance)")),
        "seconds_convergence": ("load", ref["coarse"]["seconds_total"], _a("s", "wall time of the convergence-grid case")),
    }
    attrs = {f"scene_{k}": v for k, v in dataclasses.asdict(vset).items()
             if isinstance(v, (int, float, str)) and not isinstance(v, bool)}
    attrs.update({
        "title": f"g2tom against the full-field elastic contact of a rough sphere ({vset.surface} surface; Barber's analogy)",
        "g2tom_version": __version__, "git_commit": git_commit() or "unknown",
        "default_discretization": default_spots, "default_model": "greenwood",
        "reference": "tamaas non-periodic Boussinesq operator; Polonsky-Keer contact; punch conductance by CG",
        "resistance_scale": scale_r, "force_scale": scale_f, "mu": vset.mu,
        "failed_cases": "; ".join(ref["failed"]) or "none",
        "skipped_g2tom": "; ".join(g2tom["skipped"]) or "none",
        "g2tom_clean": "asperities: 1 / (g2tom's mean clean conductance over its own asperity draws); "
                       "surface_asperities: each realization's surface asperities in g2tom's cells (exact); "
                       "discrete: each realization's surface asperities as coupled caps (exact); others: "
                       "the clean cube entry",
        "surface": "GW: Poisson asperities of density eta, heights N(0, sigma^2), paraboloidal tips of radius beta",
    })
    return xr.Dataset(data, coords=coords, attrs=attrs)


def ratios(ratio: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Geometric mean, min, max and count over the last-but-one axis (realization) of the finite positive values."""
    ok = np.isfinite(ratio) & (ratio > 0)
    logs = np.where(ok, np.log(np.where(ok, ratio, 1.0)), 0.0)
    count = ok.sum(axis=-2)
    with np.errstate(invalid="ignore", divide="ignore"):
        gm = np.exp(logs.sum(axis=-2) / count)
    lo = np.where(count > 0, np.min(np.where(ok, ratio, np.inf), axis=-2), np.nan)
    hi = np.where(count > 0, np.max(np.where(ok, ratio, -np.inf), axis=-2), np.nan)
    return gm, lo, hi, count
