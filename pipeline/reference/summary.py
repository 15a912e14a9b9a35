"""The validation's labelled dataset (validate.nc) and the ratio statistics of the report.

Part 1's ratios are g2tom / full field at equal force, per realization; the report gives their
geometric mean and range over the realizations where both resistances are finite (an open
circuit, R = +inf, is counted, not averaged). Part 2's variables come from
:func:`g2tom.reference.ensemble.variables`; every variable's units and long name from
:mod:`g2tom.reference.variables`.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import xarray as xr

from g2tom import __version__
from g2tom.fitting.ensemble import log_standard_error
from g2tom.reference import scene
from g2tom.reference.variables import variable
from g2tom.store import git_commit

__all__ = ["dataset", "ratios", "reference_arrays", "part1_ratios", "REFERENCE"]

#: The reference's solvers by solver (validate.nc's ``reference`` attribute, with the device).
REFERENCE = {
    "tamaas": "tamaas non-periodic Boussinesq operator; Polonsky-Keer contact; punch conductance by CG",
    "g2tom": "g2tom's non-periodic Boussinesq operator (Love's coefficients, zero-padded FFT), Polonsky-Keer "
             "contact and punch conductance by CG",
}


def reference_arrays(vset: scene.ValidationSet, everything: list, done: dict) -> dict[str, Any]:
    """Part 1's records as arrays: the main grid's (realization, load) and (xi, lambda, realization,
    load), the convergence grid's (load) under ``coarse``, and the failed cases' names and reasons."""
    shape = (len(vset.realizations), len(vset.deltas))
    out: dict[str, Any] = {k: np.full(shape, np.nan) for k in _MAIN}
    out["resistance"] = np.full((len(vset.xi), len(vset.lambdas)) + shape, np.nan)
    coarse = {k: np.full(len(vset.deltas), np.nan) for k in ("resistance_clean", "seconds_total", "barber_ratio", "side")}
    out["failed"] = [f"{case.name}: {done[case]['error']}" for case in everything if "error" in done[case]]
    for case in everything:
        rec = done[case]
        if case.ensemble:
            continue
        if case.n != vset.n_grid:
            for k in coarse:
                coarse[k][case.load] = rec.get(k, np.nan)
            continue
        i = vset.realizations.index(case.realization)
        for k in _MAIN:
            out[k][i, case.load] = rec.get(k, np.nan)
        out["resistance"][:, :, i, case.load] = np.asarray(rec["resistance"], float)
    out["coarse"] = coarse
    return out


def part1_ratios(g2tom: dict[str, Any], ref: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Part 1's ratios g2tom / full field at equal force: clean (discretization, model, realization,
    load) and oxidized (discretization, model, xi, lambda, realization, load); NaN where both are
    open circuits (inf / inf)."""
    with np.errstate(invalid="ignore"):
        return g2tom["clean"] / ref["resistance_clean"][None, None], g2tom["resistance"] / ref["resistance"][None, None]


#: The main grid's per-case record fields kept as (realization, load) arrays.
_MAIN = ("force", "delta", "contact_area", "resistance_clean", "side", "seconds_contact", "seconds_total",
         "seconds_cpu")


def dataset(vset: scene.ValidationSet, everything: list, done: dict, g2tom: dict[str, np.ndarray],
            default: dict[str, str], part2: dict[str, tuple] | None = None) -> xr.Dataset:
    """validate.nc: part 1 (the reference and g2tom per realization and load, ratios, convergence,
    wall times) and part 2's variables ``part2`` (:func:`g2tom.reference.ensemble.variables`).

    ``default``: the validated scenario's ``name``, ``model`` (its words), ``discretization`` (part
    1's name for its spots: ``discrete`` for the discrete model) and ``resistance_model`` (cube.model).
    """
    ref = reference_arrays(vset, everything, done)
    scale_r = 2.0 * vset.rho / np.sqrt(vset.radius * vset.sigma)
    scale_f = vset.force_scale
    coords = {
        "load": variable("load", np.arange(len(vset.deltas))),
        "realization": variable("realization", np.asarray(vset.realizations)),
        "xi": variable("xi", np.asarray(vset.xi, float)),
        "lambda": variable("lambda", np.asarray(vset.lambdas, float)),
        "discretization": variable("discretization", np.asarray(vset.discretizations)),
        "model": variable("model", np.asarray(vset.models)),
        "grid": variable("grid", np.array([vset.n_grid, vset.convergence_grid or vset.n_grid])),
        "force": variable("force", g2tom["force"]),
        "force_normalized": variable("force_normalized", g2tom["force"] / scale_f),
        "delta_g2tom": variable("delta_g2tom", np.asarray(vset.deltas) * vset.sigma),
    }
    clean_ratio, ox_ratio = part1_ratios(g2tom, ref)
    fine = ref["resistance_clean"][0]
    few = "NaN with fewer than two finite ratios"
    data = {
        "force_reference": variable("force_reference", ref["force"]),
        "delta_reference": variable("delta_reference", ref["delta"]),
        "contact_area": variable("contact_area", ref["contact_area"]),
        "window_side": variable("window_side", ref["side"]),
        "window_side_convergence": variable("window_side_convergence", ref["coarse"]["side"]),
        "resistance_reference_clean": variable("resistance_reference_clean", ref["resistance_clean"]),
        "resistance_reference": variable("resistance_reference", ref["resistance"], comment="+inf: open circuit"),
        "resistance_g2tom_clean": variable("resistance_g2tom_clean", g2tom["clean"]),
        "resistance_g2tom": variable("resistance_g2tom", g2tom["resistance"], comment="+inf: open circuit"),
        "ratio_clean": variable("ratio_clean", clean_ratio),
        "ratio": variable("ratio", ox_ratio, comment="+inf: only g2tom open; 0: only the full field open; NaN: both"),
        "ratio_clean_standard_error": variable("ratio_clean_standard_error", log_standard_error(clean_ratio, axis=-2),
                                               comment=few),
        "ratio_standard_error": variable("ratio_standard_error", log_standard_error(ox_ratio, axis=-2), comment=few),
        "resistance_convergence": variable("resistance_convergence",
                                           np.stack([fine, ref["coarse"]["resistance_clean"]])),
        "convergence_change": variable("convergence_change", ref["coarse"]["resistance_clean"] / fine - 1.0),
        "barber_ratio": variable("barber_ratio", ref["coarse"]["barber_ratio"], **({} if vset.hardness is None else {
            "comment": "K: the unloading stiffness, dF/d(-delta) of the heights flattened where p = H, pressed "
                       "elastically (the loading slope is lower)"})),
        "seconds_contact": variable("seconds_contact", ref["seconds_contact"]),
        "seconds_case": variable("seconds_case", ref["seconds_total"]),
        "seconds_cpu_case": variable("seconds_cpu_case", ref["seconds_cpu"]),
        "seconds_convergence": variable("seconds_convergence", ref["coarse"]["seconds_total"]),
    }
    if part2:
        data.update(part2)
        count = part2["resistance_ensemble_clean"][1].shape[0]
        coords["ensemble_realization"] = variable("ensemble_realization", np.arange(count))
    attrs = {f"scene_{k}": v for k, v in dataclasses.asdict(vset).items()
             if isinstance(v, (int, float, str)) and not isinstance(v, bool)}
    attrs.update({
        "title": "g2tom against the full-field "
                 + ("elastic contact" if vset.hardness is None else scene.capped_contact(vset.hardness))
                 + f" of a rough sphere ({vset.surface} surface; Barber's analogy)",
        "g2tom_version": __version__, "git_commit": git_commit() or "unknown",
        "default_discretization": default["discretization"], "default_model": default["resistance_model"],
        "validated_scenario": default["name"], "validated_model": default["model"],
        "reference": f"{REFERENCE[vset.solver]}; on the {vset.device}",
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
