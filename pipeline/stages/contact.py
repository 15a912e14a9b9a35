"""Stage 1, contact: the Greenwood–Tripp solution for every approach, its Hertz reference and spots.

Writes ``<data_dir>/contact.nc`` with dims ``delta`` and ``r`` (continuous fields) and
``y``, ``x`` (spot cells). See :func:`build` for the variables.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.compute import ComputeOptions
from pipeline.config import AUTO, ConfigError, Scenario
from pipeline.domains import resolve
from pipeline.physics import greenwood_tripp as gt
from pipeline.physics import hertz, spots
from pipeline.physics.asperity import area_fraction, asperity_pressure
from pipeline.physics.grid import cell_centres
from pipeline.physics.indenter import profile
from pipeline.store import write_dataset

__all__ = ["build", "run", "radial_grid", "indenter_profile", "solve_scenario", "fields"]

#: Rigid gap (units of sigma) beyond which the graded grid coarsens: F_{3/2}(4) / F_{3/2}(0) ~ 1e-5.
_FINE_GAP = 4.0
_FIELD = ("delta", "r")
_SPOTS = ("delta", "y", "x")


def indenter_profile(scenario: Scenario, r: np.ndarray) -> np.ndarray:
    """The scenario's indenter profile z(r), m."""
    ind = scenario.indenter
    return profile(
        r,
        ind.shape,
        radius=ind.radius,
        cone_angle=ind.cone_angle,
        punch_radius=ind.punch_radius,
        edge_radius=ind.edge_radius,
    )


def radial_grid(scenario: Scenario, n_radial: int | None = None) -> np.ndarray:
    """Radial nodes of the solve, m (``contact.radial_grid``, ``n_radial`` overrides the scenario)."""
    c = scenario.contact
    n = c.n_radial if n_radial is None else n_radial
    r_max = c.r_max * scenario.indenter.radius
    if c.radial_grid == "uniform":
        return gt.radial_nodes(n, r_max)
    probe = np.linspace(0.0, r_max, 4097)
    gap = min(scenario.deltas) + indenter_profile(scenario, probe)
    reach = gap < _FINE_GAP * scenario.roughness.sigma
    r_fine = probe[np.nonzero(reach)[0][-1]] + probe[1] if reach.any() else probe[1]
    return gt.graded_nodes(n, r_max, r_fine)


def _layer(scenario: Scenario) -> gt.Layer:
    rough = scenario.roughness
    return gt.Layer(rough.sigma, rough.eta, rough.beta, scenario.material.E_star)


def solve_scenario(
    scenario: Scenario, *, solver: str | None = None, n_radial: int | None = None,
    tolerance: float | None = None,
) -> tuple[np.ndarray, list[gt.Solution]]:
    """Radial nodes (m) and the Greenwood–Tripp solution of every approach.

    ``solver``, ``n_radial`` and ``tolerance`` override the scenario (used by the benchmark).
    """
    if scenario.contact.r_max == AUTO:
        scenario = resolve(scenario)
    c = scenario.contact
    r = radial_grid(scenario, n_radial)
    matrix = gt.influence_matrix(r, scenario.material.E_star)
    sols = gt.solve(
        matrix,
        indenter_profile(scenario, r),
        scenario.deltas,
        _layer(scenario),
        solver=solver or c.solver,
        tolerance=tolerance or c.tolerance,
        max_iterations=c.max_iterations,
        relaxation=c.relaxation,
        fixed_point_tolerance=c.fixed_point_tolerance,
    )
    return r, sols


def fields(scenario: Scenario, r: np.ndarray, sols: list[gt.Solution]) -> dict[str, np.ndarray]:
    """Displacement, separation (m), pressure (Pa), area fraction over (delta, r), force (N)."""
    rough = scenario.roughness
    u = np.stack([s.displacement for s in sols])
    h = np.asarray(scenario.deltas)[:, None] + indenter_profile(scenario, r)[None, :] + u
    p = asperity_pressure(h, rough.sigma, rough.eta, rough.beta, scenario.material.E_star)
    return {
        "u": u,
        "h": h,
        "p": p,
        "area": area_fraction(h, rough.sigma, rough.eta, rough.beta),
        "force": p @ gt.force_weights(r),
    }


def _cell_area_fraction(scenario: Scenario, r: np.ndarray, u: np.ndarray, nodal_area: np.ndarray,
                        r_cells: np.ndarray) -> np.ndarray:
    """A* at the cell centres, (delta, y, x), by the scenario's interpolation rule."""
    rough = scenario.roughness
    try:
        spots.check_inside(r, r_cells)
    except ValueError as exc:
        raise ConfigError(f"contact.window = {scenario.contact.window!r}: {exc}") from None
    if scenario.contact.area_interpolation == "area_fraction":
        return spots.interpolate_linear(r, nodal_area, r_cells)
    u_cells = spots.interpolate_smooth(r, u, r_cells)
    deltas = np.asarray(scenario.deltas)[:, None, None]
    h_cells = deltas + indenter_profile(scenario, r_cells)[None] + u_cells
    return area_fraction(h_cells, rough.sigma, rough.eta, rough.beta)


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


def _var(dims: tuple[str, ...], data: np.ndarray, long_name: str, units: str) -> tuple:
    """An xarray variable tuple with CF long_name and units."""
    return (dims, np.asarray(data), {"long_name": long_name, "units": units})


def build(scenario: Scenario) -> xr.Dataset:
    """Solve the contact problem of ``scenario`` and collect every field (pure, in memory).

    Returns
    -------
    xarray.Dataset
        Coordinates delta (m), delta_sigma, r (m), y, x (m); fields over (delta, r):
        pressure, displacement, separation, area_fraction, hertz_pressure,
        hertz_displacement, hertz_separation; over delta: force, force_normalized,
        hertz_radius, holm_radius, roughness_parameter, iterations, residual, converged;
        over (delta, y, x): spot_area, spot_radius; over r: profile. ``auto`` domains are
        resolved first (:func:`pipeline.domains.resolve`).
    """
    scenario = resolve(scenario)
    r, sols = solve_scenario(scenario)
    failed = [d / scenario.roughness.sigma for d, s in zip(scenario.deltas, sols) if not s.converged]
    if failed:
        warnings.warn(f"contact: the {scenario.contact.solver} solver did not converge for "
                      f"delta/sigma = {', '.join(f'{v:.3g}' for v in failed)}", stacklevel=2)
    f = fields(scenario, r, sols)
    x = cell_centres(scenario.n_cells, scenario.cell_size)
    cells = _cell_area_fraction(scenario, r, f["u"], f["area"], spots.cell_radii(x, x))
    spot_area = spots.spot_areas(cells, scenario.cell_size)
    data_vars = {
        **_continuous_vars(scenario, r, f),
        **_scalar_vars(scenario, f["force"], sols),
        "spot_area": _var(_SPOTS, spot_area, "spot contact area A*(r_i) dx^2", "m2"),
        "spot_radius": _var(_SPOTS, spots.spot_radii(spot_area), "spot radius sqrt(A_i / pi)", "m"),
    }
    data_vars["holm_radius"] = _var(
        ("delta",), spots.holm_greenwood_radius(data_vars["spot_radius"][1], scenario.cell_size),
        "Holm-Greenwood radius alpha_HG of all spots (Eq. 13)", "m")
    deltas = np.asarray(scenario.deltas)
    coords = {
        "delta": ("delta", deltas, {"long_name": "initial separation of the tip from the mean plane "
                                    "(negative: interpenetration)", "units": "m"}),
        "delta_sigma": ("delta", deltas / scenario.roughness.sigma,
                        {"long_name": "approach delta / sigma", "units": "1"}),
        "r": ("r", r, {"long_name": "radial coordinate", "units": "m"}),
        "y": ("y", x, {"long_name": "cell centre y", "units": "m"}),
        "x": ("x", x, {"long_name": "cell centre x", "units": "m"}),
    }
    attrs = {"cell_size": scenario.cell_size, "hertz_reference": "sphere only (NaN otherwise)"}
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _continuous_vars(scenario: Scenario, r: np.ndarray, f: dict[str, np.ndarray]) -> dict:
    """The (delta, r) fields, the profile and the Hertz reference fields."""
    ref = _hertz(scenario, r, f["force"])
    return {
        "pressure": _var(_FIELD, f["p"], "mean asperity contact pressure (Eq. 16)", "Pa"),
        "displacement": _var(_FIELD, f["u"], "total elastic normal displacement of both surfaces (Eq. 18)", "m"),
        "separation": _var(_FIELD, f["h"], "separation of the mean planes, delta + profile + displacement", "m"),
        "area_fraction": _var(_FIELD, f["area"], "real contact area fraction A* (Eq. 21 with the 1/2)", "1"),
        "profile": _var(("r",), indenter_profile(scenario, r),
                        f"undeformed indenter profile ({scenario.indenter.shape})", "m"),
        "hertz_pressure": _var(_FIELD, ref["p"], "Hertz pressure at the same force", "Pa"),
        "hertz_displacement": _var(_FIELD, ref["u"], "Hertz displacement at the same force", "m"),
        "hertz_separation": _var(_FIELD, ref["gap"], "Hertz gap between the deformed surfaces", "m"),
        "hertz_radius": _var(("delta",), ref["a"], "Hertz contact radius at the same force", "m"),
        "roughness_parameter": _var(
            ("delta",), hertz.roughness_parameter(scenario.roughness.sigma, scenario.indenter.radius, ref["a"]),
            "roughness parameter sigma R* / a^2", "1"),
    }


def _scalar_vars(scenario: Scenario, force: np.ndarray, sols: list[gt.Solution]) -> dict:
    """Force, normalized force (Eq. 25) and the solver's report, over delta."""
    d = ("delta",)
    return {
        "force": _var(d, force, "normal force 2 pi integral p r dr", "N"),
        "force_normalized": _var(d, force / scenario.force_scale, "normalized force 2F / (E* sqrt(R* sigma^3)) (Eq. 25)", "1"),
        "iterations": _var(d, np.array([s.iterations for s in sols], dtype=np.int32),
                           f"{scenario.contact.solver} iterations", "1"),
        "residual": _var(d, np.array([s.residual for s in sols]),
                         "final relative residual max|u - M p(u)| / max|M p(u)|", "1"),
        "converged": _var(d, np.array([s.converged for s in sols], dtype=np.int8),
                          "1 if the solver met its tolerance", "1"),
    }


def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Build the contact dataset and write ``<data_dir>/contact.nc`` atomically.

    ``options`` is accepted for the stage interface; the stage is under a second of dense
    linear algebra in one process, so it does not use dask.
    """
    return write_dataset(build(scenario), data_dir, "contact", scenario)
