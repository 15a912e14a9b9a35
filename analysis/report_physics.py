"""Report sections on the physics: Barber's check of the clean surface, how g2tom's numbers differ from
the paper's (the chain of biases measured by ``g2tom bench --only biases``), the curve model, the
validation against the full elastic contact, the atlas, and Greenwood's form against the point model."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.analysis.report_atlas import atlas_blocks  # the atlas section lives in its own module
from g2tom.analysis.report_blocks import Block, markdown_blocks, table
from g2tom.config import Scenario
from g2tom.store import StaleInputError, read_stage

__all__ = ["atlas_blocks", "barber_blocks", "bias_blocks", "curve_blocks", "point_blocks", "validation_blocks"]


def curve_blocks(fits: xr.Dataset) -> list[Block]:
    """Section "The curve model": ln R'(ln F') per cell, what the predictor answers with by default."""
    blocks = [Block("h2", "The curve model (the predictor's default)")]
    if "curve_order" not in fits:
        return blocks + [Block("p", "Not available: fits.nc has no curve model (re-run `g2tom fits`).")]
    order = fits["curve_order"].values
    within = fits["curve_within"].values
    error = fits["curve_max_error"].values
    orders = ", ".join(f"{int(o)}: {int(np.sum(order == o))}" for o in np.unique(order) if o > 0)
    residual = fits["fit_residual_rms"].values
    blocks.append(Block("p", (
        f"ln R' = sum_k c_k (ln F')^k per (xi, lambda) cell, fitted to the {fits.attrs.get('reduction', 'reduction')} "
        f"over the steps {fits.attrs.get('fit_range', '')}, the lowest order within 3 % of every fitted step "
        f"(else within the step's interval). Cells by order: {orders}. Within 3 %: {int(np.sum(within == 1))} "
        f"of {within.size}; within the interval only: {int(np.sum(within == 2))}; neither: {int(np.sum(within == 0))}. "
        f"Largest error over cells and steps: {100 * float(np.nanmax(error)):.2f} %. The power law of Eq. 25 "
        f"(kept, `--model power_law`) leaves an RMS log residual of {100 * float(np.nanmin(residual)):.1f}-"
        f"{100 * float(np.nanmax(residual)):.1f} %: Barber's curve bends over the paper's range.")))
    return blocks


def validation_blocks(data_dir: Path) -> list[Block]:
    """Section "Against the full elastic contact": ``g2tom validate``'s sections and figures (the GW
    surface, and the random-process surface), when they ran."""
    blocks = [Block("h2", "Against the full elastic contact (g2tom validate)")]
    folders = [(Path(data_dir) / name, label) for name, label in
               (("validate", "GW surface"), ("validate_random_process", "Gaussian self-affine surface"))]
    ran = [(f, label) for f, label in folders if (f / "validate.md").is_file()]
    if not ran:
        return blocks + [Block("p", "Not available: run `make validate` (about 15 min per surface; `make validate "
                                    "VALIDATE=--quick` for 256^2 checks in a minute).")]
    for folder, label in ran:
        blocks += markdown_blocks((folder / "validate.md").read_text(), label)
        if (folder / "validate.png").is_file():
            blocks.append(Block("img", f"R' against F' ({label}): the full-field reference (each realization) and "
                                       "g2tom's discretizations and models", src=f"{folder.name}/validate.png"))
    return blocks


def bias_blocks(data_dir: Path) -> list[Block]:
    """Section "How g2tom's numbers differ from the paper's, and why", from ``bench/biases.json``."""
    blocks = [Block("h2", "How g2tom's numbers differ from the paper's, and why")]
    path = Path(data_dir) / "bench" / "biases.json"
    if not path.is_file():
        return blocks + [Block("p", "Not available: run `g2tom bench --only biases` (part of `make run`).")]
    result = json.loads(path.read_text())
    chain = result["chain"] + [result["side"]]
    loads = chain[0]["loads_N"]
    study = result["study"]
    blocks.append(Block("p", (
        "From the published study's conventions to today's default, one change at a time, every run on the same "
        f"oxide fields ({study['oxide.n_realizations']} fixed realizations per (xi, lambda), seeds shared; the "
        "spectral period changes the fields' lattice by design). alpha and gamma: the geometric-mean power law over "
        f"the steps with F >= {study['fits.min_force']:g} N; R: geometric mean (mOhm) at the load steps nearest "
        f"{', '.join(f'{f:.4g}' for f in loads)} N. The last row replaces expected spots by asperities drawn per "
        "realization. The discrete rows solve each surface's own coupled caps at the same forces (100 surfaces, "
        "one per realization) and then count oxide per spot by its clean share f of the contact disc instead "
        "of on/off at its centre: as the disc of that area (radius a sqrt(f)), then as the circular segment of "
        "that share (radius a h(f), the default: an oxide edge crosses a spot as a chord, and of all shapes of "
        "one area the disc conducts least). Both are refused with grid spots: a grid spot "
        "stands for the expected sum of a cell's asperity radii at one cell centre, not for one contact disc, "
        "so it has no disc whose clean share could be counted.")))
    rows = [[r["step"], r["n_cells"], r["clean"]["alpha"], r["clean"]["gamma"],
             *[1e3 * v for v in r["clean"]["resistance"]]] for r in chain]
    blocks.append(table(["step (clean surface)", "cells", "alpha", "gamma",
                         *[f"R at {f:.4g} N" for f in loads]], rows))
    cells = [(c["xi"], c["lambda"]) for c in chain[0]["cells"]]
    rows = [[r["step"], *[f"{c['alpha']:.4g} / {c['gamma']:.3g}" for c in r["cells"]],
             *[1e3 * v for v in r["cells"][-1]["resistance"]]] for r in chain]
    last = cells[-1]
    blocks.append(table(["step (oxidized)", *[f"alpha / gamma at xi {x:g}, lambda {lam:g}" for x, lam in cells],
                         *[f"R at {f:.4g} N (xi {last[0]:g}, lambda {last[1]:g})" for f in loads]], rows))
    return blocks


def barber_blocks(data_dir: Path, scenario: Scenario) -> list[Block]:
    """Section "Barber's theorem": the clean conductance of each model over K / (E* rho*) at every step."""
    blocks = [Block("h2", "Barber's theorem: the clean surface's check")]
    try:
        contact = read_stage(data_dir, "contact", scenario)
        cube = read_stage(data_dir, "cube", scenario, select=lambda ds: ds.drop_dims("realization"))  # the clean surface
    except (FileNotFoundError, StaleInputError, OSError) as exc:
        return blocks + [Block("p", f"Not available: {exc}")]
    discrete = "discrete_barber_conductance" in contact
    # discrete asperities: each surface's own K, averaged over the pool as the cube averages its conductance
    barber = (contact["discrete_barber_conductance"].mean("surface") if discrete
              else contact["barber_conductance"]).values
    names = [n for n in cube.data_vars if n.startswith("conductance_clean_")]
    ratios = {n.removeprefix("conductance_clean_"): cube[n].values / barber for n in names}
    spots = "discrete" if discrete else contact.attrs.get("spots", "mean_area")
    system = ("coupled caps of each surface of the pool (the mean over its surfaces of conductance and of "
              "K / (E* rho*))" if discrete else "discretised Greenwood-Tripp system")
    blocks.append(Block("p", (
        f"Barber's theorem is exact for a clean elastic contact: conductance = K / (E* rho*), with K = -dF/d delta "
        f"the exact linearisation of the {system}. With this run's spots ({spots}), the "
        "clean conductance over Barber's, worst step: " + "; ".join(
            f"{name.replace('_', ' + ')} {_worst(r)}" for name, r in ratios.items()) + ".")))
    if spots == "asperities":
        blocks.append(Block("p", "Asperity spots: the mean conductance over the drawn surfaces; a surface with no "
                                 "touching asperity conducts nothing (open circuit), counted at 0."))
    force = contact["force"].values
    rows = [[f"{force[k]:.4g}", *[f"{r[k]:.4f}" for r in ratios.values()]] for k in range(force.size)]
    blocks.append(table(["F (N)", *[f"{n.replace('_', ' + ')} / Barber" for n in ratios]], rows))
    return blocks


def _worst(ratio: np.ndarray) -> str:
    """The ratio farthest from 1, as text ('not applicable' when all NaN)."""
    finite = ratio[np.isfinite(ratio)]
    if finite.size == 0:
        return "not applicable"
    worst = finite[np.argmax(np.abs(finite - 1.0))]
    return f"{worst:.4f} ({100 * (worst - 1):+.2f} %)"


def point_blocks(data_dir: Path) -> list[Block]:
    """alpha and gamma of both models on ``make compare``'s shared ensemble, and their ratio."""
    from g2tom.analysis.figures_point import COMPARE, load_comparison

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
    blocks.append(table(["xi", "lambda", "alpha G", "alpha point", "ratio", "gamma G", "gamma point",
                          "gamma difference"], rows))
    return blocks
