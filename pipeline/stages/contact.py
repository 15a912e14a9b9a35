"""Stage 1, contact: the Greenwood–Tripp solution for every approach, its Hertz reference and spots.

Writes ``<data_dir>/contact.nc`` with dims ``delta`` and ``r`` (continuous fields) and
``y``, ``x`` (spot cells). See :func:`build` for the variables.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.compute import ComputeOptions, single_threaded
from g2tom.config import ConfigError, Scenario
from g2tom.contact_solution import fields, indenter_profile, solve_with_stiffness
from g2tom.before_work.domains import resolve
from g2tom.physics import greenwood_tripp as gt
from g2tom.physics import hertz, spot_models, spots
from g2tom.physics.asperity import area_fraction
from g2tom.physics.grid import cell_centres
from g2tom.models import contact_model
from g2tom.scene import scene_plasticity
from g2tom.stages.schema import SCHEMA, SPOT_RADIUS_LONG_NAMES, labelled
from g2tom.store import write_dataset

__all__ = ["build", "run"]


def _cell_spots(scenario: Scenario, r: np.ndarray, u: np.ndarray, nodal_area: np.ndarray,
                r_cells: np.ndarray) -> dict[str, np.ndarray]:
    """Separation (m), spot area (m^2) and spot radius (m) at the cell centres, (delta, y, x).

    The separation is the spline of the displacement at the cells; the area is A* dx^2 with A*
    by ``contact.area_interpolation``; the radius by ``contact.spots``
    (:func:`g2tom.physics.spot_models.cell_radius`; ``mean_area`` keeps ``sqrt(A / pi)`` of
    the interpolated area).
    """
    rough = scenario.roughness
    try:
        spots.check_inside(r, r_cells)
    except ValueError as exc:
        raise ConfigError(f"contact.window = {scenario.contact.window!r}: {exc}") from None
    u_cells = spots.interpolate_smooth(r, u, r_cells)
    deltas = np.asarray(scenario.deltas)[:, None, None]
    h_cells = deltas + indenter_profile(scenario, r_cells)[None] + u_cells
    if scenario.contact.area_interpolation == "area_fraction":
        fraction = spots.interpolate_linear(r, nodal_area, r_cells)
    else:
        fraction = area_fraction(h_cells, rough.sigma, rough.eta, rough.beta)
    area = spots.spot_areas(fraction, scenario.cell_size)
    if scenario.contact.spots == "mean_area":
        radius = spots.spot_radii(area)
    else:
        radius = spot_models.cell_radius(h_cells, scenario.contact.spots, rough.sigma, rough.eta, rough.beta)
    return {"separation": h_cells, "area": area, "radius": radius}


def _hertz(scenario: Scenario, r: np.ndarray, force: np.ndarray) -> dict[str, np.ndarray]:
    """Hertz reference at the same force (sphere only; NaN for other profiles)."""
    radius, e_star = scenario.indenter.radius, scenario.material.E_star
    if scenario.indenter.shape != "sphere":
        nan = np.full((len(force), len(r)), np.nan)
        return {"a": np.full(len(force), np.nan), "p": nan, "u": nan, "gap": nan}
    a = hertz.hertz_radius(force, radius, e_star)
    col_a, col_f = a[:, None], force[:, None]
    u = hertz.hertz_displacement(r[None, :], col_a, col_f, e_star)
    gap = indenter_profile(scenario, r)[None, :] - hertz.hertz_approach(col_a, radius) + u
    return {"a": a, "p": hertz.hertz_pressure(r[None, :], col_a, col_f), "u": u, "gap": gap}


def _var(name: str, data: np.ndarray, **slots: str) -> tuple:
    """An xarray variable tuple of contact.nc: dims and CF long_name and units from the schema."""
    return labelled(SCHEMA["contact"][name], np.asarray(data), **slots)


@single_threaded
def build(scenario: Scenario, options: ComputeOptions = ComputeOptions(progress=False)) -> xr.Dataset:
    """Solve the contact problem of ``scenario`` and collect every field (pure, in memory).

    Returns
    -------
    xarray.Dataset
        Coordinates delta (m), delta_sigma, r (m), y, x (m); fields over (delta, r):
        pressure, displacement, separation, area_fraction, hertz_pressure,
        hertz_displacement, hertz_separation; over delta: force, force_normalized,
        hertz_radius, holm_radius, roughness_parameter, iterations, residual, converged,
        stiffness (N/m) and barber_conductance (S);
        over (delta, y, x): spot_area, spot_radius (by ``contact.spots``), spot_separation; over r: profile. ``auto`` domains are
        resolved first (:func:`g2tom.before_work.domains.resolve`). And what the contact model adds at
        the same forces (:meth:`g2tom.models.ContactModel.contact_pool`: the discrete model's pool of
        surfaces, its solves run where ``options`` says).
    """
    scenario = resolve(scenario)
    r, sols, stiffness = solve_with_stiffness(scenario)
    failed = [d / scenario.roughness.sigma for d, s in zip(scenario.deltas, sols) if not s.converged]
    if failed:
        warnings.warn(f"contact: the {scenario.contact.solver} solver did not converge for "
                      f"delta/sigma = {', '.join(f'{v:.3g}' for v in failed)}", stacklevel=2)
    f = fields(scenario, r, sols)
    x = cell_centres(scenario.n_cells, scenario.cell_size)
    cells = _cell_spots(scenario, r, f["u"], f["area"], spots.cell_radii(x, x))
    data_vars = {
        **_continuous_vars(scenario, r, f),
        **_scalar_vars(scenario, f["force"], sols),
        "stiffness": _var("stiffness", stiffness),
        "barber_conductance": _var("barber_conductance", stiffness / (scenario.material.E_star * scenario.material.rho)),
        "spot_area": _var("spot_area", cells["area"]),
        "spot_radius": _var("spot_radius", cells["radius"], spot_radius=SPOT_RADIUS_LONG_NAMES[scenario.contact.spots]),
        "spot_separation": _var("spot_separation", cells["separation"]),
    }
    data_vars["holm_radius"] = _var("holm_radius", spots.holm_greenwood_radius(data_vars["spot_radius"][1], scenario.cell_size))
    deltas = np.asarray(scenario.deltas)
    coords = {
        "delta": _var("delta", deltas),
        "delta_sigma": _var("delta_sigma", deltas / scenario.roughness.sigma),
        "r": _var("r", r),
        "y": _var("y", x),
        "x": _var("x", x),
    }
    attrs = {"cell_size": scenario.cell_size, "hertz_reference": "sphere only (NaN otherwise)",
             "spots": scenario.contact.spots, "model": scenario.contact.model}
    pool_vars, pool_coords, pool_attrs = contact_model(scenario).contact_pool(scenario, f["force"], float(deltas.min()),
                                                                             options)
    data_vars.update(pool_vars)
    coords.update(pool_coords)
    attrs.update(pool_attrs)
    data_vars.update(_plasticity_vars(scenario))
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _plasticity_vars(scenario: Scenario) -> dict[str, tuple]:
    """The plasticity index and a cap's first yield where a hardness is known, and the hardness the caps
    are capped at where they are (:class:`g2tom.scene.Plasticity`); none for an elastic scene of
    unknown hardness."""
    known = scene_plasticity(scenario)
    if known.index is None:
        return {}
    out = {"plasticity_index": _var("plasticity_index", np.float64(known.index)),
           "yield_interference": _var("yield_interference", np.float64(known.yield_interference))}
    if known.hardness is not None:
        out["hardness"] = _var("hardness", np.float64(known.hardness))
    return out


def _continuous_vars(scenario: Scenario, r: np.ndarray, f: dict[str, np.ndarray]) -> dict:
    """The (delta, r) fields, the profile and the Hertz reference fields."""
    ref = _hertz(scenario, r, f["force"])
    return {
        "pressure": _var("pressure", f["p"]),
        "displacement": _var("displacement", f["u"]),
        "separation": _var("separation", f["h"]),
        "area_fraction": _var("area_fraction", f["area"]),
        "profile": _var("profile", indenter_profile(scenario, r), shape=scenario.indenter.shape),
        "hertz_pressure": _var("hertz_pressure", ref["p"]),
        "hertz_displacement": _var("hertz_displacement", ref["u"]),
        "hertz_separation": _var("hertz_separation", ref["gap"]),
        "hertz_radius": _var("hertz_radius", ref["a"]),
        "roughness_parameter": _var(
            "roughness_parameter", hertz.roughness_parameter(scenario.roughness.sigma, scenario.indenter.radius, ref["a"])),
    }


def _scalar_vars(scenario: Scenario, force: np.ndarray, sols: list[gt.Solution]) -> dict:
    """Force, normalized force (Eq. 25) and the solver's report, over delta."""
    return {
        "force": _var("force", force),
        "force_normalized": _var("force_normalized", force / scenario.force_scale),
        "iterations": _var("iterations", np.array([s.iterations for s in sols], dtype=np.int32),
                           solver=scenario.contact.solver),
        "residual": _var("residual", np.array([s.residual for s in sols])),
        "converged": _var("converged", np.array([s.converged for s in sols], dtype=np.int8)),
    }


@single_threaded
def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Build the contact dataset and write ``<data_dir>/contact.nc`` atomically.

    The Greenwood–Tripp solve is under a second of dense linear algebra in one process; the
    discrete model's pool of surfaces runs where ``options`` says.
    """
    return write_dataset(build(scenario, options), data_dir, "contact", scenario)
