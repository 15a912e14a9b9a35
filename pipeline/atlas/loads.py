"""The atlas's load steps, chosen in F' so that every scene covers the same range of F'.

A scenario's approaches are evenly spaced in delta/sigma (``loading.delta_max`` ..
``loading.delta_min``), and F'(delta) depends on the scene (on mu: Greenwood–Tripp's layer is
stiffer or softer), so a fixed delta range covers another F' range in every scene (the first
atlas spanned F' 0.67-10.3 in all of them). Here each scene gets its own approaches: the ends
are the approaches at which Greenwood–Tripp's force is F' = :data:`FORCE_RANGE` widened by
:data:`END_MARGIN` (the root of ln F'(delta) on a fast solve, :func:`approaches_at`), and ``loading.n_delta`` steps lie evenly in delta between them. The
discrete model solves its surfaces at the Greenwood–Tripp forces of the same approaches
(the discrete model, :class:`g2tom.models.Discrete`), so both models get the same F' steps. The fast solve
(:func:`g2tom.models.discrete_cost.probe`: 400 graded nodes, its own radial domain) and the stage's (``contact.n_radial`` nodes, the resolved
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

from g2tom.models.discrete_cost import probe
from g2tom.compute import single_threaded
from g2tom.config import Scenario

__all__ = ["FORCE_RANGE", "END_MARGIN", "normalized_forces", "approaches_at", "loading_for_range"]

#: The range of F' = 2F/(E* sqrt(R* sigma^3)) every scene of the atlas covers (electrical
#: connectors sit below F' 1; the paper's own range is 0.075-18.8).
FORCE_RANGE = (0.05, 20.0)
#: Relative margin beyond FORCE_RANGE at which the end steps are placed (the fast solve that
#: finds them and the stage's solve differ by ~1e-4 in F').
END_MARGIN = 0.02
#: Approaches (delta/sigma) of the solve the root search starts from: F' from ~1e-6 to ~1e4 on
#: every scene of the atlas's box.
_GRID = tuple(np.arange(5.0, -9.01, -0.5))
#: The ends found so far, by the parameters that set F'(delta) (a scene's scenario is asked for often).
_ENDS: dict[str, tuple[float, float]] = {}
#: Newton steps at most that polish the spline's root.
_POLISH = 6


def normalized_forces(scenario: Scenario, delta_sigma: np.ndarray) -> np.ndarray:
    """Greenwood–Tripp's F' at the approaches ``delta_sigma`` (units of sigma, lightest first,
    evenly spaced), by one fast solve (:func:`probe`)."""
    return probe(scenario, delta_sigma)[1]["force"] / scenario.force_scale


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
