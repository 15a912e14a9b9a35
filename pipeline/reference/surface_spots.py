"""g2tom with the GW surface's own asperities as its spots: the ``surface_asperities`` discretization.

On the GW surface the reference knows every asperity (position, height). Placing them in g2tom's
cells (the nearest centre; several in one cell make one spot of their summed radius,
:func:`g2tom.physics.spot_models.placed_radius`) at g2tom's Greenwood–Tripp separation gives
g2tom's answer on the very surface the full field solves, realization by realization. Against the
``asperities`` discretization (heights drawn per cell) it removes the sampling of the surface;
what remains against the full field is Greenwood–Tripp's averaging (the separation of the mean
planes, the asperities' elastic interaction through it) and the resistance model (Greenwood's
form or the point model, spots at cell centres).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from g2tom.physics import spot_models
from g2tom.reference import scene, surfaces
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube as cube_stage
from g2tom.models import lattice_cube
from g2tom.scene import FieldSource

__all__ = ["SURFACE_ASPERITIES", "spot_radii", "g2tom_resistances"]

#: The discretization's name in validate.nc (not a ``contact.spots`` value: it needs a known surface).
SURFACE_ASPERITIES = "surface_asperities"


def spot_radii(vset: scene.ValidationSet, realization: int, centres: np.ndarray, separation: np.ndarray) -> np.ndarray:
    """Spot radii (m, (delta, y, x)) of the realization's GW asperities in g2tom's cells.

    Parameters
    ----------
    vset
        The validation set (a GW surface).
    realization
        Surface realization index: the asperities are :func:`g2tom.reference.scene.rough_sphere`'s.
    centres
        g2tom's cell centres along one axis, m.
    separation
        g2tom's separation of the mean planes at the cell centres, m, (delta, y, x).
    """
    if vset.surface != "gw":
        raise ValueError(f"{SURFACE_ASPERITIES} needs the GW surface, whose asperities are known (not {vset.surface!r})")
    tips = surfaces.gw_asperities(vset.side, vset.eta, vset.sigma, vset.beta, scene.surface_stream(vset, realization))
    cells = spot_models.nearest_cells(tips.x, tips.y, centres)
    return spot_models.placed_radius(tips.z, cells, separation, vset.beta)


def g2tom_resistances(vset: scene.ValidationSet, model: str) -> xr.Dataset:
    """g2tom's resistances of the set with the surfaces' own asperities, exact (whole window, no crop).

    Returns ``force`` (delta, N), ``resistance_clean`` (realization, delta) and ``resistance``
    (xi, lambda, delta, realization), ohm (+inf: open circuit), and ``contact_extent`` (delta, m)
    as :func:`g2tom.reference.scene.g2tom_resistances`. Asperities beyond g2tom's window are
    dropped: the window holds the Greenwood–Tripp contact.
    """
    scenario = scene.g2tom_scenario(vset, model, "asperities")
    contact = contact_stage.build(scenario)
    _, _, settings = cube_stage.work_settings(scenario, contact)
    realizations = np.asarray(vset.realizations)
    radius = np.stack([spot_radii(vset, int(k), contact["x"].values, settings.separation) for k in realizations])
    clean = lattice_cube.clean_terms(radius, radius, settings).resistance  # (realization, delta)
    oxidized = lattice_cube.exact_terms(FieldSource.of(scenario), realizations, radius, radius, settings)["resistance"]
    return xr.Dataset({
        "force": contact["force"],
        "resistance_clean": scene.case_variable("resistance_clean", clean),
        "resistance": scene.case_variable("resistance", oxidized),
        "contact_extent": scene.contact_extent(contact),
    })
