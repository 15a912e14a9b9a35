"""g2tom's discrete model on the GW surface's own asperities: the ``discrete`` discretization of validate.

On the GW surface the reference knows every asperity. The discrete model
(:mod:`g2tom.physics.discrete_contact`) solves those very caps, coupled through the half-space,
at g2tom's forces (the Greenwood–Tripp forces of the set's approaches, where the reference is
solved too), and the cube's discrete chunk (:func:`g2tom.models.discrete_cube.discrete_chunk`)
counts oxide per spot by the set's ``spot_rule`` (the validated scenario's ``disc`` or ``segment``,
:func:`with_rule_of`) on g2tom's own fields. Against the full field it measures the discrete model
itself, surface by surface: the caps' point-load coupling, the resistance model and the spot rule.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import xarray as xr

from g2tom.before_work import load_scenario
from g2tom.physics import discrete_contact as dc
from g2tom.physics.cap_law import CappedCap
from g2tom.reference import scene, surfaces
from g2tom.scene import FieldSource
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube as cube_stage
from g2tom.models import Discrete
from g2tom.models.discrete_cube import DiscretePool, clean_pool, discrete_chunk

__all__ = ["DISCRETE", "RULES", "with_rule_of", "surface_pool", "g2tom_resistances"]

#: The discretization's name in validate.nc: the discrete model's.
DISCRETE = Discrete.name
#: The oxide rules the discretization takes (a spot's share of its contact disc); the set's own
#: is the validated scenario's where that is one of them, else ``disc``.
RULES = ("disc", "segment")


def with_rule_of(vset: scene.ValidationSet, config: str) -> scene.ValidationSet:
    """``vset`` with the spot rule of the validated scenario ``config`` (``disc`` where it has none of :data:`RULES`)."""
    rule = load_scenario(config).oxide.spot_rule
    return dataclasses.replace(vset, spot_rule=rule if rule in RULES else "disc")


def surface_pool(vset: scene.ValidationSet, realization: int, forces: np.ndarray) -> DiscretePool:
    """A one-surface pool: the realization's GW asperities (the reference's own) solved at ``forces`` (N)."""
    if vset.surface != "gw":
        raise ValueError(f"{DISCRETE} needs the GW surface, whose asperities are known (not {vset.surface!r})")
    tips = surfaces.gw_asperities(vset.side, vset.eta, vset.sigma, vset.beta, scene.surface_stream(vset, realization))
    floor = dc.coupling_floor(vset.beta, vset.sigma)
    cap = dc.cap_radius("sphere", vset.beta, radius=vset.radius)
    gap = functools.partial(dc.cap_gap, shape="sphere", beta=vset.beta, radius=vset.radius)
    law = None if vset.hardness is None else CappedCap(vset.e_star, cap, vset.hardness)
    sol = dc.solve_forces(dc.Asperities(tips.x, tips.y, tips.z), gap, np.asarray(forces, float), vset.e_star, cap,
                          floor, cap=law)
    touching = np.flatnonzero((sol.interference > 0).any(axis=0))
    return DiscretePool(tips.x[None, touching], tips.y[None, touching], sol.radii[None][..., touching],
                        np.array([touching.size]), floor)


def g2tom_resistances(vset: scene.ValidationSet, model: str) -> xr.Dataset:
    """g2tom's discrete resistances of the set on each surface's own caps.

    Returns ``force`` (delta, N), ``resistance_clean`` (realization, delta) and ``resistance``
    (xi, lambda, delta, realization), ohm (+inf: open circuit), and ``contact_extent`` (delta, m)
    as :func:`g2tom.reference.scene.g2tom_resistances`.
    """
    scenario = scene.g2tom_scenario(vset, model, "expected")
    contact = contact_stage.build(scenario)
    forces = contact["force"].values
    _, _, settings = cube_stage.work_settings(scenario, contact)
    settings = dataclasses.replace(settings, spot_rule=vset.spot_rule, model=model, contact_model=Discrete())
    source = FieldSource.of(scenario)
    xi_all = np.arange(len(vset.xi))
    clean, oxidized = [], []
    for k in vset.realizations:
        pool = surface_pool(vset, int(k), forces)
        clean.append(clean_pool(pool, vset.rho, model)["resistance"][0])
        oxidized.append(np.stack([discrete_chunk(source, a, np.array([int(k)]), xi_all, pool, settings)["resistance"][..., 0]
                                  for a in range(len(vset.lambdas))], axis=1))  # (xi, lambda, delta)
    return xr.Dataset({
        "force": contact["force"],
        "resistance_clean": scene.case_variable("resistance_clean", np.stack(clean)),
        "resistance": scene.case_variable("resistance", np.stack(oxidized, axis=-1)),
        "contact_extent": scene.contact_extent(contact),
    })
