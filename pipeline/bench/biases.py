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
   in place of Greenwood–Tripp's mean: the discrete model);
8. the disc spot rule (each spot conducts with its clean share of its contact disc, not on/off
   at its centre: radius a sqrt(f));
9. the segment spot rule (the same share, conducting as the circular segment of that share:
   radius a h(f) >= a sqrt(f); today's default);

and beside the chain, asperity spots (drawn per realization) in place of step 5. Each run
reports alpha and gamma (the geometric-mean fit over the steps with F >= 200 N) and the
geometric-mean R at three loads, clean and on a few oxidized cells.

The steps' contact is not solved again where the contact stage's file holds it
(:func:`stored_contact`): ``<data_dir>/contact.nc``, current for the run's scenario, serves each step
whose contact parameters are the scenario's but for a smaller pool (on the default scenario, the
discrete steps' 100 surfaces are the first 100 of its 256). The steps that differ only in their spots
share one Greenwood-Tripp solve (:func:`g2tom.contact_solution.shared_solves`), and the steps that meet
the same spots one solve of the clean surface (:func:`g2tom.models.shared_clean.shared_cleans`: on the
default scenario the spectral period's, the point model's and the spot rules' steps reuse the step
before's).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.contact_solution import shared_solves
from g2tom.errors import StaleInputError
from g2tom.models import Discrete
from g2tom.models.shared_clean import shared_cleans
from g2tom.config import ResolvedScenario, Scenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve, resolved
from g2tom.stages import contact, cube, fits, oxide
from g2tom.store import provenance, read_stage

__all__ = ["STEPS", "run", "stored_contact"]

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


def stored_contact(stored: ResolvedScenario, dataset: xr.Dataset, wanted: ResolvedScenario) -> xr.Dataset | None:
    """``wanted``'s contact dataset taken from ``dataset``, the contact stage's dataset of ``stored``, or
    None where ``dataset`` does not hold it.

    It holds it where the contact parameters of ``wanted`` are those of ``stored`` but for
    ``contact.surfaces``, at most ``stored``'s, and both draw the pool from the same ``oxide.seed``.
    Surface ``k`` of a pool is drawn from stream ``k`` and solved alone, so a pool of ``n`` surfaces
    is the first ``n`` of a larger one; a grown pool (``contact.pool_half_width``) is not, and is
    refused. The result is the dataset :func:`g2tom.stages.contact.build` gives for ``wanted``: the
    first ``n`` surfaces, the spots padded to their largest count, without the file's provenance.

    Parameters
    ----------
    stored
        The scenario ``dataset`` was built from.
    dataset
        contact.nc of ``stored``, loaded (:func:`g2tom.store.read_stage`).
    wanted
        The scenario whose contact is wanted.
    """
    c, n = wanted.contact, wanted.contact.surfaces
    as_stored = dataclasses.replace(wanted, contact=dataclasses.replace(c, surfaces=stored.contact.surfaces))
    if (n > stored.contact.surfaces or c.pool_half_width > 0 or wanted.oxide.seed != stored.oxide.seed
            or as_stored.config_hash("contact") != stored.config_hash("contact")):
        return None
    out = dataset.copy(deep=False)
    if "surface" in out.dims:
        out = out.isel(surface=slice(0, n))
        out = out.isel(spot=slice(0, max(1, int(out["spot_count"].max())))).copy(deep=True)  # contiguous, as solved
    written = provenance(stored, "contact")
    out.attrs = {k: v for k, v in dataset.attrs.items() if k not in written}
    return out


def _stored(scenario: Scenario, data_dir: str | Path | None) -> tuple[ResolvedScenario, xr.Dataset] | None:
    """``scenario`` resolved and its contact.nc under ``data_dir``, or None if there is none current
    (missing, stale, unreadable, unconverged: :func:`g2tom.store.read_stage`)."""
    if data_dir is None:
        return None
    scenario = resolved(scenario)
    try:
        return scenario, read_stage(data_dir, "contact", scenario)
    except StaleInputError:
        return None


def _one(overrides: dict[str, Any], contacts: dict[str, Any],
         stored: tuple[ResolvedScenario, xr.Dataset] | None) -> dict[str, Any]:
    """alpha, gamma and R at :data:`LOADS` (clean and per cell) of the published scenario with
    ``overrides``; ``contacts`` keeps the contact datasets by configuration hash (steps that change
    only the oxide or the cube share one), each taken from ``stored`` (the run's scenario and its
    contact.nc) where it holds it (:func:`stored_contact`), else solved."""
    scenario: ResolvedScenario = resolve(load_scenario("published", {**STUDY, **overrides}))
    options = ComputeOptions(progress=False)
    start = time.perf_counter()
    key = scenario.config_hash("contact")
    if key not in contacts:
        found = stored_contact(*stored, scenario) if stored else None
        contacts[key] = contact.build(scenario, options) if found is None else found
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


def run(scenario: Scenario, data_dir: str | Path | None = None) -> dict[str, Any]:
    """The chain of :data:`STEPS` and the :data:`SIDE` run (``scenario`` names the study only; its
    contact.nc under ``data_dir``, where current, stands in for the steps' contact it holds)."""
    chain, overrides, contacts = [], {}, {}
    stored = _stored(scenario, data_dir)
    with shared_solves(), shared_cleans():
        for label, change in STEPS:
            overrides = {**overrides, **change}
            chain.append({"step": label, "overrides": dict(change), **_one(overrides, contacts, stored)})
        label, after, change = SIDE
        base = {k: v for _, c in STEPS[: after + 1] for k, v in c.items()}
        side = {"step": label, "overrides": dict(change), **_one({**base, **change}, contacts, stored)}
    return {"chain": chain, "side": side, "study": STUDY,
            "note": "each step changes one thing from the previous; all runs use the same oxide fields"}
