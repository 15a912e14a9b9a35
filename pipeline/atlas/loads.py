"""The atlas's load steps, chosen in F' so that every scene covers the same range of F'.

A scenario's approaches are evenly spaced in delta/sigma (``loading.delta_max`` ..
``loading.delta_min``), and F'(delta) depends on the scene (on mu: Greenwood–Tripp's layer is
stiffer or softer), so a fixed delta range covers another F' range in every scene (the first
atlas spanned F' 0.67-10.3 in all of them). Here each scene gets its own approaches: the ends
are the approaches at which Greenwood–Tripp's force is F' = :data:`FORCE_RANGE` widened by
:data:`END_MARGIN` (the root of ln F'(delta) on a fast solve, :func:`approaches_at`), and ``loading.n_delta`` steps lie evenly in delta between them. The
discrete model solves its surfaces at the Greenwood–Tripp forces of the same approaches
(``contact.model = "discrete"``), so both models get the same F' steps. The fast solve (400
graded nodes, its own radial domain) and the stage's (``contact.n_radial`` nodes, the resolved
``r_max``) differ by far less than the margin, so every scene's steps span FORCE_RANGE.

Only the range is chosen in F': steps in between follow the even spacing in delta (exact F'
steps shared by all scenes would need a list of forces in ``[loading]``, which the scenario
format does not have).
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
from scipy.optimize import brentq

from pipeline.compute import single_threaded
from pipeline.config import Scenario

__all__ = ["FORCE_RANGE", "END_MARGIN", "probe", "normalized_forces", "expected_counts", "expected_touching", "approaches_at", "loading_for_range"]

#: The range of F' = 2F/(E* sqrt(R* sigma^3)) every scene of the atlas covers (issue 31:
#: connectors sit below F' 1; the paper's own range is 0.075-18.8).
FORCE_RANGE = (0.05, 20.0)
#: Relative margin beyond FORCE_RANGE at which the end steps are placed (the fast solve that
#: finds them and the stage's solve differ by ~1e-4 in F').
END_MARGIN = 0.02
#: Radial nodes of the fast solve.
_N_RADIAL = 400
#: Rigid gap (units of sigma) at the fast solve's outer radius: f_{3/2}(12) ~ 1e-33 of the peak.
_FAR_GAP = 12.0
#: Approaches (delta/sigma) of the solve the root search starts from: F' from ~1e-6 to ~1e4 on
#: every scene of the atlas's box.
_GRID = tuple(np.arange(5.0, -9.01, -0.5))
#: The ends found so far, by the parameters that set F'(delta) (a scene's scenario is asked for often).
_ENDS: dict[str, tuple[float, float]] = {}
#: The expected touching and candidate counts found so far, by the parameters that set them.
_COUNTS: dict[str, tuple[np.ndarray, np.ndarray]] = {}
#: Newton steps at most that polish the spline's root.
_POLISH = 6


def probe(scenario: Scenario, delta_sigma: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A fast Greenwood–Tripp solve at the approaches ``delta_sigma`` (units of sigma, lightest
    first, evenly spaced), warm-started along them: radial nodes (m) and the contact stage's fields
    (:func:`pipeline.contact_solution.fields`: separation ``h``, pressure ``p``, ``force``, ...).

    Parameters
    ----------
    scenario
        The surface, sphere and material (its loading and domains are replaced).
    delta_sigma
        Approaches delta / sigma, decreasing (negative: interpenetration).

    Raises
    ------
    ValueError
        If the approaches are not evenly spaced and decreasing.
    """
    from pipeline.contact_solution import fields, indenter_profile, solve

    deltas = np.atleast_1d(np.asarray(delta_sigma, float))
    sigma = scenario.roughness.sigma
    r = scenario.indenter.radius * 1e-6
    while (deltas.min() * sigma + float(indenter_profile(scenario, np.array([r]))[0])) < _FAR_GAP * sigma:
        r *= 1.5
    probe_scenario = dataclasses.replace(
        scenario,
        loading=dataclasses.replace(scenario.loading, delta_max=float(deltas[0]), delta_min=float(deltas[-1]),
                                    n_delta=deltas.size),
        contact=dataclasses.replace(scenario.contact, r_max=r / scenario.indenter.radius, window=1.0,
                                    radial_grid="graded", n_radial=_N_RADIAL, solver="newton"))
    if not np.allclose(np.array(probe_scenario.deltas) / sigma, deltas, rtol=0, atol=1e-9):
        raise ValueError("the approaches must be evenly spaced and decreasing")
    nodes, sols = solve(probe_scenario, tolerance=1e-10)
    return nodes, fields(probe_scenario, nodes, sols)


def normalized_forces(scenario: Scenario, delta_sigma: np.ndarray) -> np.ndarray:
    """Greenwood–Tripp's F' at the approaches ``delta_sigma`` (units of sigma, lightest first,
    evenly spaced), by one fast solve (:func:`probe`)."""
    return probe(scenario, delta_sigma)[1]["force"] / scenario.force_scale


def expected_counts(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Greenwood–Tripp's expected count of touching asperities at each of the scenario's
    approaches, 2 pi eta integral P(z > h(r)) r dr with h the solved separation (z ~ N(0, sigma^2)),
    and of candidates, the asperities above the undeformed indenter (h the rigid gap: the discrete
    solve's candidate set, displacements only lowering asperities), by one fast solve."""
    from scipy.special import erfc

    from pipeline.contact_solution import indenter_profile
    from pipeline.physics.greenwood_tripp import force_weights

    flat = scenario.flat()
    key = json.dumps({k: v for k, v in flat.items() if k.startswith(("material.", "roughness.", "indenter.",
                                                                      "loading."))}, sort_keys=True)
    if key not in _COUNTS:
        sigma = scenario.roughness.sigma
        deltas = np.asarray(scenario.deltas)
        nodes, solved = probe(scenario, deltas / sigma)
        weights = scenario.roughness.eta * force_weights(nodes)
        rigid = deltas[:, None] + indenter_profile(scenario, nodes)[None, :]
        counts = tuple(0.5 * erfc(gap / (sigma * math.sqrt(2.0))) @ weights for gap in (solved["h"], rigid))
        _COUNTS[key] = counts
    return _COUNTS[key][0].copy(), _COUNTS[key][1].copy()


def expected_touching(scenario: Scenario) -> np.ndarray:
    """Greenwood–Tripp's expected count of touching asperities at each approach (:func:`expected_counts`)."""
    return expected_counts(scenario)[0]


def approaches_at(scenario: Scenario, force_normalized: tuple[float, ...]) -> tuple[float, ...]:
    """The approaches delta / sigma at which Greenwood–Tripp's force is each ``force_normalized`` (F').

    ln F'(delta) falls monotonically with delta: it is solved once on :data:`_GRID` (warm-started
    along it), each root found on the cubic spline through it and polished by Newton steps on
    single solves (slope from the spline) until |ln F' - ln target| <= 1e-8.

    Raises
    ------
    ValueError
        If a target is not > 0 or lies outside the forces of :data:`_GRID`.
    """
    from scipy.interpolate import CubicSpline

    grid = np.array(_GRID)
    ln_f = np.log(normalized_forces(scenario, grid))
    spline = CubicSpline(-grid, ln_f)  # increasing in -delta
    out = []
    for value in force_normalized:
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"F' = {value!r} must be > 0")
        target = math.log(value)
        if not ln_f[0] < target < ln_f[-1]:
            raise ValueError(f"F' = {value:g} lies outside the forces of the approaches {grid[0]:g} .. "
                             f"{grid[-1]:g} sigma ({math.exp(ln_f[0]):.3g} .. {math.exp(ln_f[-1]):.3g})")
        k = int(np.searchsorted(ln_f, target))
        d = -brentq(lambda x: float(spline(x)) - target, -grid[k - 1], -grid[k], xtol=1e-12)
        for _ in range(_POLISH):
            error = math.log(normalized_forces(scenario, np.array([d]))[0]) - target
            if abs(error) <= 1e-8:
                break
            d += error / float(spline(-d, 1))  # d ln F' / d delta = -spline'
        else:
            raise ValueError(f"F' = {value:g}: the approach did not converge ({error:.3g} in ln F')")
        out.append(float(d))
    return tuple(out)


@single_threaded
def loading_for_range(scenario: Scenario, force_range: tuple[float, float] = FORCE_RANGE,
                      margin: float = END_MARGIN) -> Scenario:
    """``scenario`` with approaches whose Greenwood–Tripp forces span ``force_range`` (F').

    The lightest step is placed at F' = low / (1 + margin), the heaviest at high (1 + margin),
    ``loading.n_delta`` steps (kept) evenly in delta between them; the ends are rounded to 1e-6
    sigma (readable, stable parameter values).

    Raises
    ------
    ValueError
        If the range is not 0 < low < high or a bound cannot be reached.
    """
    low, high = force_range
    if not (0 < low < high and math.isfinite(high)):
        raise ValueError(f"force range {force_range!r} must be 0 < low < high")
    flat = scenario.flat()
    key = json.dumps([{k: v for k, v in flat.items() if k.startswith(("material.", "roughness.", "indenter."))},
                      low, high, margin], sort_keys=True)
    if key not in _ENDS:
        ends = approaches_at(scenario, (low / (1.0 + margin), high * (1.0 + margin)))
        _ENDS[key] = tuple(round(d, 6) for d in ends)
    delta_max, delta_min = _ENDS[key]
    loading = dataclasses.replace(scenario.loading, delta_max=delta_max, delta_min=delta_min)
    return dataclasses.replace(scenario, loading=loading)
