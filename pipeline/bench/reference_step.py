"""One full-field load step and its punch on two (device, solver) settings, the same inputs: the part
the reference's speed benchmarks (``gpu``, ``solver``) share.

The inputs are the validation's default scene (GW surface of realization 0 on the sphere) at the
load F' = :data:`LOAD` on a window of half the set's side, on an ``n x n`` grid. A contact step is
timed from rest (a fresh operator each time: both solvers start from an operator's last solution),
the punch on the step's contact set; each a median of ``repeats``, after one untimed warm-up where
asked (a GPU's cuFFT plans and kernels).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from g2tom.bench.timing import median_time
from g2tom.reference import elastic, scene
from g2tom.reference.contact import contact_at_force
from g2tom.reference.punch import punch_conductance

__all__ = ["LOAD", "Setting", "row", "largest_differences"]

#: The load, F' (the quick set's heavier step, delta/sigma = -0.5 on the GW surface).
LOAD = 4.85
#: A (device, solver, label) to time; the label prefixes its figures.
Setting = tuple[str, str, str]
#: The differences :func:`row` reports, largest first in :func:`largest_differences`.
_DIFFERENCES = ("force_difference", "delta_difference", "pressure_difference", "conductance_difference",
                "contact_pixels_differing")


def _timed(setting: Setting, heights: np.ndarray, pixel: float, force: float, repeats: int,
           warm: bool) -> dict[str, Any]:
    vset = scene.DEFAULT
    device, solver, _ = setting

    def fresh() -> Any:
        return elastic.free_surface(heights.shape[0], pixel, vset.e_star, device, solver)

    if warm:
        punch_conductance(fresh(), contact_at_force(fresh(), heights, force).contact, vset.rho)
    contact_seconds, state = median_time(lambda: contact_at_force(fresh(), heights, force), repeats)
    operator = fresh()
    punch_seconds, punch = median_time(lambda: punch_conductance(operator, state.contact, vset.rho), repeats)
    return {"contact_seconds": contact_seconds, "punch_seconds": punch_seconds, "state": state,
            "conductance": punch.conductance}


def row(n: int, candidate: Setting, baseline: Setting | None, repeats: int, baseline_repeats: int,
        warm: bool) -> dict[str, Any]:
    """The candidate's and (unless None) the baseline's seconds on an ``n x n`` grid, their ratios
    (baseline over candidate) and the candidate's largest relative differences from the baseline."""
    vset = scene.DEFAULT
    side, force = vset.side / 2.0, LOAD * vset.force_scale
    pixel = side / n
    heights = scene.rough_sphere(vset, 0, n, side)
    ours = _timed(candidate, heights, pixel, force, repeats, warm)
    label = candidate[2]
    result: dict[str, Any] = {"n": n, "pixel_m": pixel, "contact_pixels": int(ours["state"].contact.sum()),
                              f"{label}_contact_seconds": ours["contact_seconds"],
                              f"{label}_punch_seconds": ours["punch_seconds"]}
    if baseline is None:
        return result
    theirs = _timed(baseline, heights, pixel, force, baseline_repeats, warm=False)
    a, b = ours["state"], theirs["state"]
    result.update({
        f"{baseline[2]}_contact_seconds": theirs["contact_seconds"],
        f"{baseline[2]}_punch_seconds": theirs["punch_seconds"],
        "contact_ratio": theirs["contact_seconds"] / ours["contact_seconds"],
        "punch_ratio": theirs["punch_seconds"] / ours["punch_seconds"],
        "force_difference": abs(a.force / b.force - 1.0),
        "delta_difference": abs(a.delta / b.delta - 1.0),
        "pressure_difference": float(np.abs(a.pressure - b.pressure).max() / b.pressure.max()),
        "contact_pixels_differing": int((a.contact != b.contact).sum()),
        "conductance_difference": abs(ours["conductance"] / theirs["conductance"] - 1.0),
    })
    return result


def largest_differences(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The largest of each difference over the rows that have them ({} when none)."""
    compared = [r for r in rows if "contact_ratio" in r]
    return {key: max(r[key] for r in compared) for key in _DIFFERENCES} if compared else {}
