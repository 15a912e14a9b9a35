"""Domains from the solution: ``contact.r_max`` and ``contact.window`` resolved before work.

The oxide stage needs the number of cells before the contact stage runs, so ``"auto"`` is
resolved once, up front, from a fast solve at the heaviest approach (:func:`resolve`):

* **window**: the smallest odd square of cells outside of which the spots cannot change
  ``R`` by more than ``cube.crop_tolerance`` for any oxide mask (the cropping bound of
  :func:`g2tom.physics.crops.truncation_bounds`, with the scenario's interaction
  weights), at every approach (the heaviest needs the most).
* **r_max**: far enough that the window's corner cells lie inside the radial domain (with a
  margin of :data:`MARGIN_CELLS` cells) and the pressure at ``r_max`` is below
  ``crop_tolerance`` times the central pressure.

The elastic displacement only widens the gap (``u >= 0``), so the rigid gap bounds the
spots from above: the solve's grid is sized from the rigid gap, and the window from the
solution. An explicit value that truncates the contact by more than the tolerance is refused
with the value needed. The resolved scenario carries plain numbers, so its config hashes and
every output's provenance record them. :func:`solve_scenario` is the Greenwood–Tripp solve of a
scenario whose domains may still be ``auto`` (resolved first).
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np

from g2tom.before_work.window_checks import check_domains
from g2tom.config import AUTO, ConfigError, ResolvedScenario, Scenario, odd_cells
from g2tom.contact_solution import indenter_profile, solve
from g2tom.physics import crops, spot_models, spots
from g2tom.physics import greenwood_tripp as gt
from g2tom.physics.asperity import log_asperity_integral
from g2tom.physics.grid import cell_centres

__all__ = ["Domains", "resolve", "solve_scenario", "domains", "estimate_cells", "check_cell_count", "MARGIN_CELLS",
           "TOLERANCE_FLOOR"]

#: Cells between the window's corner centres and r_max (room for the spline at the corners).
MARGIN_CELLS = 2
#: The bound used when ``cube.crop_tolerance`` is 0 (keeping every nonzero float spot is unbounded).
TOLERANCE_FLOOR = 1e-12
#: Rigid gap (units of sigma) past which no asperity touches: f_1(40) = exp(-800)-small.
_FAR_GAP = 40.0
#: Radial nodes of the fast solve at the heaviest approach.
_N_RADIAL = 400
_CACHE: dict[str, "Domains"] = {}


@dataclasses.dataclass(frozen=True)
class Domains:
    """Resolved domains: r_max and window in units of R*, and what each needs.

    Attributes
    ----------
    r_max, window
        Values used (the explicit ones, or the resolved ``auto``), R*.
    r_max_needed, window_needed
        Smallest values that keep the truncation within the tolerance, R*.
    n_cells_needed
        Cells along the side of the needed window.
    window_bound
        Bound on the relative change of R from the cells outside the window used.
    """

    r_max: float
    window: float
    r_max_needed: float
    window_needed: float
    n_cells_needed: int
    window_bound: float


def _reach(scenario: Scenario) -> float:
    """Radius (m) beyond which the rigid gap at the heaviest approach exceeds :data:`_FAR_GAP` sigma."""
    sigma = scenario.roughness.sigma
    delta = min(scenario.deltas)
    r = scenario.cell_size
    while delta + float(indenter_profile(scenario, np.array([r]))[0]) < _FAR_GAP * sigma:
        r *= 2.0
    return r


def _weights(scenario: Scenario, radius: np.ndarray) -> tuple[np.ndarray, float]:
    """Interaction weights of ``radius`` under ``cube.weights`` and the bound's margin."""
    if scenario.cube.weights == "radius":
        return radius, 1.0
    return np.pi * radius**2, crops.CROP_MARGIN


def _needed_cells(scenario: Scenario, radius: np.ndarray, tolerance: float) -> tuple[int, np.ndarray]:
    """Smallest odd side keeping every map's bound within ``tolerance``, and the bounds per side."""
    weights, margin = _weights(scenario, radius)
    bounds = np.max(
        [crops.truncation_bounds(a, w, scenario.cell_size, margin) for a, w in zip(radius, weights)],
        axis=0,
    )
    k = int(np.flatnonzero(bounds <= tolerance)[0])
    return max(2 * k + 1, 3), bounds


def _cell_grid(scenario: Scenario, half_width: float) -> tuple[int, np.ndarray]:
    """Odd side and cell radii of the centred grid covering [-half_width, half_width]^2."""
    n = 2 * int(math.ceil(half_width / scenario.cell_size)) + 1
    x = cell_centres(n, scenario.cell_size)
    return n, spots.cell_radii(x, x)


def _spot_radii(scenario: Scenario, gap: np.ndarray) -> np.ndarray:
    """The cells' spot radii at separation ``gap`` (m) under ``contact.spots`` (for ``asperities``
    their mean over realizations: the window bounds the expected truncation)."""
    rough = scenario.roughness
    return spot_models.cell_radius(gap, scenario.contact.spots, rough.sigma, rough.eta, rough.beta)


def _solve_heaviest(scenario: Scenario, r_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Radial nodes (m) and the displacement (m) at the heaviest approach on [0, r_max]."""
    loading = dataclasses.replace(scenario.loading, delta_max=scenario.loading.delta_min, n_delta=1)
    contact = dataclasses.replace(scenario.contact, r_max=r_max / scenario.indenter.radius,
                                  radial_grid="graded", window=1.0)
    fast = Scenario.of(scenario, loading=loading, contact=contact)  # plain: this window is not the resolved one
    r, sols = solve(fast, solver="newton", n_radial=_N_RADIAL, tolerance=1e-8)
    return r, sols[0].displacement


def _pressure_radius(scenario: Scenario, tolerance: float) -> float:
    """Radius (m) past which the rigid-gap pressure is below ``tolerance`` x the peak pressure."""
    sigma = scenario.roughness.sigma
    r = np.linspace(0.0, _reach(scenario), 4097)
    log_p = log_asperity_integral((min(scenario.deltas) + indenter_profile(scenario, r)) / sigma, 1.5)
    small = log_p < math.log(tolerance) + log_p.max()
    beyond = np.flatnonzero(~small)
    return float(r[min(beyond[-1] + 1, r.size - 1)])


def _rigid_grid_side(scenario: Scenario) -> int:
    """Cells per side of the rigid-gap grid that :func:`domains` builds."""
    return 2 * int(math.ceil(_reach(scenario) / scenario.cell_size)) + 1


#: Bytes per cell of the rigid-gap grid (radii, gap, area fraction and their temporaries).
_GRID_BYTES = 80.0


#: Per indenter shape, the parameters that set how far its rigid gap stays within reach of the
#: asperities, each with the sign of its effect on the grid (+1: a larger value widens it).
_INDENTER_REACH: dict[str, tuple[tuple[str, int], ...]] = {
    "sphere": (("radius", 1),),
    "cone": (("cone_angle", -1),),
    "flat_punch": (("punch_radius", 1), ("edge_radius", 1)),
}
#: Units of the parameters that set the reach, for the message.
_REACH_UNITS = {"radius": "m", "cone_angle": "rad", "punch_radius": "m", "edge_radius": "m", "sigma": "m"}


def _departure(value: float, default: float, sign: int) -> float:
    """How far ``value`` lies from its bundled ``default`` towards a wider grid (log ratio)."""
    return sign * math.log(value / default)


def _reach_fit(scenario: Scenario, section: str, name: str, sign: int, memory: float) -> float:
    """The value of ``<section>.<name>`` nearest the scenario's at which the rigid-gap grid fits ``memory``.

    Found by stepping away from the value by factors 2, 4, 16, 256, ... (the square of the last, so
    that any finite value is reached in a dozen steps) until the grid fits, then bisecting in log; a
    cone's angle stays below pi/2. NaN if no value fits.
    """
    def fits(value: float) -> bool:
        trial = Scenario.of(scenario, **{section: dataclasses.replace(getattr(scenario, section), **{name: value})})
        side = _rigid_grid_side(trial)
        return _GRID_BYTES * side * side <= memory  # a float product: the side can exceed 1e154

    bad = getattr(getattr(scenario, section), name)
    step = 2.0 ** -sign
    good = bad * step
    for _ in range(12):
        if name == "cone_angle":
            good = min(good, (bad + math.pi / 2) / 2)
        if not 0.0 < good < math.inf:
            return math.nan
        if fits(good):
            break
        bad, good, step = good, good * step * step, step * step
    else:
        return math.nan
    for _ in range(60):
        middle = math.sqrt(bad) * math.sqrt(good)  # the product of two tiny values would underflow
        bad, good = (bad, middle) if fits(middle) else (middle, good)
    return good


def check_cell_count(scenario: Scenario, memory: float) -> None:
    """Refuse a scene so wide or a cell size so fine that the rigid-gap grid of :func:`domains`
    cannot fit in ``memory``.

    The grid spans the radius at which the indenter's rigid gap reaches 40 sigma (set by the
    indenter: its radius, cone angle or punch; and by sigma) in cells of 1/sqrt(eta). The refusal
    blames the parameter that lies farthest from its bundled default towards a wider grid, with the
    value that fits, and names the other way out.

    Raises
    ------
    ConfigError
        Naming ``roughness.eta`` (the cell pitch is 1/sqrt(eta)), ``roughness.sigma`` or the indenter's
        parameter (``indenter.radius``, ``indenter.cone_angle``, ``indenter.punch_radius`` or
        ``indenter.edge_radius`` by shape), its value, and the value that fits.
    """
    if AUTO not in (scenario.contact.window, scenario.contact.r_max):
        return
    side = _rigid_grid_side(scenario)
    need = _GRID_BYTES * side * side
    if need <= memory:
        return
    ind = scenario.indenter
    eta = scenario.roughness.eta
    eta_fix = f"roughness.eta <= about {eta * (memory / need):.3g} (m-2)"
    cells = f"{side}" if side < 10**7 else f"{side:.3g}"
    grid = (f"the contact needs a grid of about {cells} x {cells} cells ({need / 2**30:.3g} GiB, "
            f"{memory / 2**30:.3g} GiB available)")
    candidates = [("indenter", name, sign) for name, sign in _INDENTER_REACH[ind.shape]] + [("roughness", "sigma", 1)]

    def departure(candidate: tuple[str, str, int]) -> float:
        section, name, sign = candidate
        default = getattr(type(getattr(scenario, section))(), name)
        return _departure(getattr(getattr(scenario, section), name), default, sign)

    section, name, sign = max(candidates, key=departure)
    key, value, unit = f"{section}.{name}", getattr(getattr(scenario, section), name), _REACH_UNITS[name]
    fit = _reach_fit(scenario, section, name, sign, memory)
    reach_fix = f"{key} {'<=' if sign > 0 else '>='} about {fit:.3g} ({unit})" if math.isfinite(fit) else None
    eta_departure = _departure(eta, type(scenario.roughness)().eta, 1)
    if reach_fix and departure((section, name, sign)) > eta_departure:
        raise ConfigError(
            f"{key} = {value:g} ({unit}) is out of range for this machine: the {ind.shape.replace('_', ' ')}'s "
            f"rigid gap stays within 40 sigma of the asperities out to r = {_reach(scenario):.3g} m, so {grid}; "
            f"it must be {reach_fix.removeprefix(f'{key} ')} (or {eta_fix})"
        )
    raise ConfigError(
        f"roughness.eta = {eta:g} is out of range for this machine: {grid}; it must be "
        f"{eta_fix.removeprefix('roughness.eta ')}" + (f" (or {reach_fix})" if reach_fix else "")
    )


def estimate_cells(scenario: Scenario) -> int:
    """Cheap upper estimate of the ``auto`` window's cells per side (no solve, 1-D rigid gap).

    The bound of :func:`g2tom.physics.crops.truncation_bounds` with the rigid gap's
    spots (an upper bound of the solved ones) summed over rings of radius r (2 pi r dr / h^2
    cells), the square of half-side r containing the disc of radius r.
    """
    h = scenario.cell_size
    tol = max(scenario.cube.crop_tolerance, TOLERANCE_FLOOR)
    r = np.linspace(0.0, _reach(scenario), 8193)
    a = _spot_radii(scenario, min(scenario.deltas) + indenter_profile(scenario, r))
    w, margin = _weights(scenario, a)
    ring = 2.0 * np.pi * r * (r[1] - r[0]) / h**2
    outside_w = np.cumsum((w * ring)[::-1])[::-1]
    total_a, total_w = float(np.sum(a * ring)), float(outside_w[0])
    if not total_w > 0:
        return 3
    bound = 4.0 * outside_w * margin * total_a / (total_w * np.pi * h)
    r_w = r[int(np.flatnonzero(bound <= tol)[0])] if (bound <= tol).any() else r[-1]
    return max(2 * int(math.ceil(r_w / h)) + 1, 3)


def _key(scenario: Scenario) -> str:
    flat = scenario.flat()
    wanted = ("material.", "roughness.", "indenter.", "loading.", "contact.", "cube.weights",
              "cube.crop_tolerance")
    return json.dumps({k: v for k, v in flat.items() if k.startswith(wanted)}, sort_keys=True)


def _round_up(value: float) -> float:
    """``value`` rounded up to 4 significant digits (stable, readable parameter values)."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 3)
    return float(f"{math.ceil(value / scale * (1 - 1e-12)) * scale:.4g}")


def domains(scenario: Scenario) -> Domains:
    """The needed and the used r_max and window of ``scenario`` (cached per parameter set).

    Raises
    ------
    ConfigError
        If an explicit ``contact.window`` or ``contact.r_max`` truncates the contact by more
        than ``cube.crop_tolerance``, naming the parameter and the value needed.
    """
    key = _key(scenario)
    if key in _CACHE:
        return _CACHE[key]
    tol = max(scenario.cube.crop_tolerance, TOLERANCE_FLOOR)
    radius_star, h = scenario.indenter.radius, scenario.cell_size
    # Rigid gap: an upper bound of every spot, so its window holds the solved one.
    _, r_cells = _cell_grid(scenario, _reach(scenario))
    rigid = _spot_radii(scenario, min(scenario.deltas) + indenter_profile(scenario, r_cells))[None]
    n_rigid, _ = _needed_cells(scenario, rigid, tol)
    corner_rigid = math.sqrt(2.0) * (n_rigid - 1) / 2.0 * h + MARGIN_CELLS * h
    r_solve = max(corner_rigid, _pressure_radius(scenario, tol))
    # Solved spots at the heaviest approach, on the rigid window's grid.
    r_nodes, u = _solve_heaviest(scenario, r_solve)
    x = cell_centres(n_rigid, h)
    r_cells = spots.cell_radii(x, x)
    gap = min(scenario.deltas) + indenter_profile(scenario, r_cells) + spots.interpolate_smooth(r_nodes, u, r_cells)
    radius = _spot_radii(scenario, gap)[None]
    n_needed, bounds = _needed_cells(scenario, radius, tol)
    window_needed = n_needed * h / radius_star
    c = scenario.contact
    window = _round_up(window_needed) if c.window == AUTO else float(c.window)
    n_used = odd_cells(window * radius_star, h)
    if n_used < n_needed:
        k = (n_used - 1) // 2
        bound = float(bounds[k]) if k < bounds.size else 0.0
        raise ConfigError(
            f"contact.window = {c.window!r} truncates the contact: the spots outside it can change R by "
            f"up to {bound:.3g} > cube.crop_tolerance = {scenario.cube.crop_tolerance:g}; it must be "
            f">= {_round_up(window_needed):.4g} (R*, {n_needed} cells), or 'auto'"
        )
    corner = math.sqrt(2.0) * (n_used - 1) / 2.0 * h + MARGIN_CELLS * h
    r_max_needed = max(corner, _pressure_radius(scenario, tol)) / radius_star
    r_max = _round_up(r_max_needed) if c.r_max == AUTO else float(c.r_max)
    if r_max < r_max_needed * (1 - 1e-9) and c.r_max != AUTO:
        raise ConfigError(
            f"contact.r_max = {c.r_max!r} truncates the contact: the pressure beyond it or the "
            f"window's corner cells (window = {window:.4g} R*) need r_max >= {_round_up(r_max_needed):.4g} (R*), "
            f"or 'auto'"
        )
    k_used = (n_used - 1) // 2
    result = Domains(r_max, window, r_max_needed, window_needed, n_needed,
                     float(bounds[k_used]) if k_used < bounds.size else 0.0)
    _CACHE[key] = result
    return result


def resolved(scenario: Scenario) -> ResolvedScenario:
    """``scenario`` itself where it is a :class:`~g2tom.config.ResolvedScenario` already, else
    :func:`resolve` of it: what a stage called from Python with a loaded scenario does first."""
    return scenario if isinstance(scenario, ResolvedScenario) else resolve(scenario)


def resolve(scenario: Scenario) -> ResolvedScenario:
    """``scenario`` with numeric ``contact.r_max`` and ``contact.window`` (``auto`` resolved).

    Explicit values are checked (an explicit window or r_max that truncates the contact by
    more than ``cube.crop_tolerance`` is refused) and kept exactly as given, so a scenario
    with both explicit keeps its results bit for bit, and resolving a resolved scenario gives
    it back. The result is a :class:`~g2tom.config.ResolvedScenario`, also when both were
    explicit.

    Raises
    ------
    ConfigError
        Naming the parameter and the value needed.
    """
    d = domains(scenario)
    contact = dataclasses.replace(scenario.contact, r_max=d.r_max, window=d.window)
    if scenario.contact.r_max != AUTO:
        contact = dataclasses.replace(contact, r_max=scenario.contact.r_max)
    if scenario.contact.window != AUTO:
        contact = dataclasses.replace(contact, window=scenario.contact.window)
    out = ResolvedScenario.of(scenario, contact=contact)
    check_domains(out)
    return out


def solve_scenario(
    scenario: Scenario, *, solver: str | None = None, n_radial: int | None = None,
    tolerance: float | None = None,
) -> tuple[np.ndarray, list[gt.Solution]]:
    """Radial nodes (m) and the Greenwood–Tripp solution of every approach, ``auto`` domains
    resolved first (see :func:`g2tom.contact_solution.solve`)."""
    if scenario.contact.r_max == AUTO:
        scenario = resolve(scenario)
    return solve(scenario, solver=solver, n_radial=n_radial, tolerance=tolerance)
