"""The Greenwood–Tripp solve of a scenario: its indenter profile, radial grid, solution and fields.

The glue between a :class:`g2tom.config.Scenario` and :mod:`g2tom.physics.greenwood_tripp`,
shared by the contact stage and by :mod:`g2tom.before_work.domains` (which sizes the domains from a fast
solve before any stage runs); no I/O. :func:`solve` needs numeric domains
(:func:`g2tom.before_work.domains.resolve` resolves ``auto``;
:func:`g2tom.before_work.domains.solve_scenario` resolves, then solves). :func:`fields` are the
solution's separation, pressure, area fraction and force, as the contact stage stores them.
Inside :func:`shared_solves`, :func:`solve_with_stiffness` solves each distinct system once (the
benchmarks that build the contact of several scenarios on one solve).
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import Any

import numpy as np

from g2tom.config import AUTO, Scenario
from g2tom.physics import greenwood_tripp as gt
from g2tom.physics import radial_grid as rg
from g2tom.physics.asperity import area_fraction, asperity_pressure
from g2tom.physics.indenter import profile
from g2tom.compute import SharedResults

__all__ = ["indenter_profile", "radial_grid", "layer", "solve", "solve_with_stiffness", "shared_solves", "fields"]

#: Rigid gap (units of sigma) beyond which the graded grid coarsens: F_{3/2}(4) / F_{3/2}(0) ~ 1e-5.
_FINE_GAP = 4.0
#: The solutions :func:`solve_with_stiffness` keeps inside :func:`shared_solves`, by their inputs.
_SOLVES = SharedResults()


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
        return rg.radial_nodes(n, r_max)
    probe = np.linspace(0.0, r_max, 4097)
    gap = min(scenario.deltas) + indenter_profile(scenario, probe)
    reach = gap < _FINE_GAP * scenario.roughness.sigma
    r_fine = probe[np.nonzero(reach)[0][-1]] + probe[1] if reach.any() else probe[1]
    return rg.graded_nodes(n, r_max, r_fine)


def layer(scenario: Scenario) -> gt.Layer:
    """The asperity layer and modulus of ``scenario``."""
    rough = scenario.roughness
    return gt.Layer(rough.sigma, rough.eta, rough.beta, scenario.material.E_star)


def _system(
    scenario: Scenario, solver: str | None, n_radial: int | None, tolerance: float | None,
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Radial nodes (m), the indenter profile at them (m) and the solver's settings: with the
    approaches and the layer, every input of the solve."""
    c = scenario.contact
    if c.r_max == AUTO:
        raise ValueError("contact.r_max = 'auto' must be resolved first (g2tom.before_work.domains.resolve)")
    r = radial_grid(scenario, n_radial)
    settings = {"solver": solver or c.solver, "tolerance": tolerance or c.tolerance, "max_iterations": c.max_iterations,
                "relaxation": c.relaxation, "fixed_point_tolerance": c.fixed_point_tolerance}
    return r, indenter_profile(scenario, r), settings


def _solve(
    scenario: Scenario, solver: str | None, n_radial: int | None, tolerance: float | None,
) -> tuple[np.ndarray, np.ndarray, list[gt.Solution]]:
    """Radial nodes (m), influence matrix (m/Pa) and the solution of every approach."""
    r, z, settings = _system(scenario, solver, n_radial, tolerance)
    matrix = rg.influence_matrix(r, scenario.material.E_star)
    sols = gt.solve(matrix, z, scenario.deltas, layer(scenario), **settings)
    return r, matrix, sols


def solve(
    scenario: Scenario, *, solver: str | None = None, n_radial: int | None = None,
    tolerance: float | None = None,
) -> tuple[np.ndarray, list[gt.Solution]]:
    """Radial nodes (m) and the Greenwood–Tripp solution of every approach.

    ``solver``, ``n_radial`` and ``tolerance`` override the scenario (used by the benchmark).

    Raises
    ------
    ValueError
        If ``contact.r_max`` is still ``auto``.
    """
    r, _, sols = _solve(scenario, solver, n_radial, tolerance)
    return r, sols


def solve_with_stiffness(scenario: Scenario) -> tuple[np.ndarray, list[gt.Solution], np.ndarray]:
    """:func:`solve` and the contact stiffness ``K = -dF/d delta`` of every approach (N/m), by the
    exact linearisation of the discretised system (:func:`g2tom.physics.greenwood_tripp.stiffness`);
    inside :func:`shared_solves`, a copy of the solution of an earlier scenario with the same inputs."""
    def compute() -> tuple[np.ndarray, list[gt.Solution], np.ndarray]:
        r, matrix, sols = _solve(scenario, None, None, None)
        return r, sols, gt.stiffness(matrix, indenter_profile(scenario, r), scenario.deltas, layer(scenario), sols, r)

    if not _SOLVES.active:  # gathering the inputs costs a grid and a profile: only where they are kept
        return compute()
    r, z, settings = _system(scenario, None, None, None)
    return _SOLVES.once(compute, r, z, np.asarray(scenario.deltas, float), layer(scenario), sorted(settings.items()))


def shared_solves() -> AbstractContextManager[None]:
    """Inside the block, :func:`solve_with_stiffness` solves each distinct system once.

    Scenarios whose solves have the same inputs (radial nodes, profile, approaches, layer and solver
    settings; ``contact.spots``, ``contact.window`` and ``contact.model`` are not among them) share one
    solve: the later ones get a copy of its nodes (m), solutions and stiffness (N/m), equal to
    solving again. Nested blocks share the outer one's solutions.
    """
    return _SOLVES.block()


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
        "force": p @ rg.force_weights(r),
    }
