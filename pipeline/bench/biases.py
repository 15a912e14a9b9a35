"""How g2tom's numbers differ from the paper's, and why: each bias measured on the same fields.

A chain of runs from the published study's conventions to today's default, each changing one
thing, all on the same oxide fields (same seeds; realization ``k`` of a lambda is one field):

1. ``published``: the published code's conventions (area weights, coarse fixed-point
   Greenwood-Tripp, A* interpolated linearly, the window as the field's period, mean-area spots);
2. radius weights (Greenwood's Eq. 13, as printed);
3. converged Greenwood-Tripp (Newton to 1e-10 on 720 graded nodes, the separation interpolated);
4. the spectral period (the field lattice converged: a period that resolves the spectrum);
5. expected spots (the discretization that obeys Barber's theorem: today's default);
6. the point model (Greenwood's closed form is a bound; the exact solve of the same spots);
7. discrete asperities (each surface's own caps coupled through the half-space, at the same forces,
   in place of Greenwood–Tripp's mean; design note 11);
8. the disc spot rule (each spot conducts with its clean share of its contact disc, not on/off
   at its centre: radius a sqrt(f));
9. the segment spot rule (the same share, conducting as the circular segment of that share:
   radius a h(f) >= a sqrt(f); today's default);

and beside the chain, asperity spots (drawn per realization) in place of step 5. Each run
reports alpha and gamma (the geometric-mean fit over the steps with F >= 200 N) and the
geometric-mean R at three loads, clean and on a few oxidized cells.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from g2tom.compute import ComputeOptions
from g2tom.models import Discrete
from g2tom.config import ResolvedScenario, Scenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.stages import contact, cube, fits, oxide

__all__ = ["STEPS", "run"]

#: The chain: (label, overrides added to the previous step's).
STEPS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("published conventions", {}),
    ("radius weights (Eq. 13)", {"cube.weights": "radius"}),
    ("converged Greenwood-Tripp", {"contact.solver": "newton", "contact.n_radial": 720, "contact.radial_grid": "graded",
                                   "contact.area_interpolation": "separation", "contact.r_max": "auto",
                                   "contact.window": "auto"}),
    ("spectral period (field lattice)", {"oxide.period": "spectral"}),
    ("expected spots (Barber; paper_gt)", {"contact.spots": "expected"}),
    ("point model (Greenwood's bound)", {"cube.model": "point"}),
    ("discrete asperities (coupled caps)", {"contact.model": Discrete.name}),
    ("disc spot rule (a sqrt(f))", {"oxide.spot_rule": "disc"}),
    ("segment spot rule (a h(f); the default)", {"oxide.spot_rule": "segment"}),
)
#: Beside the chain: asperity spots in place of expected spots (step 5).
SIDE = ("asperity spots (instead of expected)", 4, {"contact.spots": "asperities"})
#: The common study: a few cells, a fixed ensemble on the same seeds, the published fit range.
STUDY = {"oxide.xi": [0.5, 0.9], "oxide.lambda": [1.0, 9.0], "oxide.ensemble": "fixed",
         "oxide.n_realizations": 100, "contact.surfaces": 100, "fits.fit_range": "force", "fits.min_force": 200.0,
         "fits.n_bootstrap": 100, "surrogate.method": "paper"}
#: Loads (N) at which R is reported: the nearest load steps.
LOADS = (273.0, 1339.0, 9699.0)


def _one(overrides: dict[str, Any], contacts: dict[str, Any]) -> dict[str, Any]:
    """alpha, gamma and R at :data:`LOADS` (clean and per cell) of the published scenario with
    ``overrides``; ``contacts`` keeps the contact datasets by configuration hash (steps that change
    only the oxide or the cube share one)."""
    scenario: ResolvedScenario = resolve(load_scenario("published", {**STUDY, **overrides}))
    options = ComputeOptions(progress=False)
    start = time.perf_counter()
    key = scenario.config_hash("contact")
    if key not in contacts:
        contacts[key] = contact.build(scenario, options)
    contact_ds = contacts[key]
    cube_ds = cube.build(scenario, contact_ds, oxide.build(scenario, options), options)
    fits_ds = fits.build(scenario, cube_ds)
    force = contact_ds["force"].values
    steps = [int(np.argmin(np.abs(np.log(force / f)))) for f in LOADS]
    gm = fits_ds["geometric_mean"].transpose("xi", "lambda", "delta").values
    cells = [{"xi": float(x), "lambda": float(lam),
              "alpha": float(fits_ds["alpha"].sel(xi=x, **{"lambda": lam})),
              "gamma": float(fits_ds["gamma"].sel(xi=x, **{"lambda": lam})),
              "resistance": [float(gm[i, j, k]) for k in steps]}
             for i, x in enumerate(fits_ds["xi"].values) for j, lam in enumerate(fits_ds["lambda"].values)]
    clean = {"alpha": float(fits_ds["alpha_clean"]), "gamma": float(fits_ds["gamma_clean"]),
             "resistance": [float(cube_ds["resistance_clean"].values[k]) for k in steps]}
    return {"clean": clean, "cells": cells, "loads_N": [float(force[k]) for k in steps],
            "n_cells": scenario.n_cells, "seconds": time.perf_counter() - start}


def run(scenario: Scenario) -> dict[str, Any]:
    """The chain of :data:`STEPS` and the :data:`SIDE` run (``scenario`` names the study only)."""
    chain, overrides, contacts = [], {}, {}
    for label, change in STEPS:
        overrides = {**overrides, **change}
        chain.append({"step": label, "overrides": dict(change), **_one(overrides, contacts)})
    label, after, change = SIDE
    base = {k: v for _, c in STEPS[: after + 1] for k, v in c.items()}
    side = {"step": label, "overrides": dict(change), **_one({**base, **change}, contacts)}
    return {"chain": chain, "side": side, "study": STUDY,
            "note": "each step changes one thing from the previous; all runs use the same oxide fields"}
