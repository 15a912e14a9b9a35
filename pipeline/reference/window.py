"""Each case's window: the centred square that holds its full-field contact, so light loads get fine pixels.

The set's window (``ValidationSet.side``) holds the heaviest load's contact; a light load touches
on a few asperities near the axis, whose micro-contacts span only a pixel or two on it (on the
random-process surface, halving the grid step changed the lightest load's clean R by 23 %).
So each case first solves its contact on a coarse probe grid (:func:`probe_grid`) of the set's
window, measures how far the contact reaches along x or y, and solves on a window of
:data:`MARGIN` times that reach plus :data:`PAD_SPACINGS` asperity spacings, at its own grid
size: the same number of pixels, finer. The probe depends only on the set, the realization and
the force, so the main and convergence grids of a case share the window, and halving the grid
step is measured on one window. Should the contact still reach the window's edge, the window
grows by :data:`GROWTH` (at most to the set's window) and the solve is repeated.
"""

from __future__ import annotations

import math

import numpy as np

from g2tom.physics.grid import cell_centres
from g2tom.reference import elastic, scene
from g2tom.reference.contact import ContactReachesEdge, ContactState, contact_at_force

__all__ = ["MARGIN", "PAD_SPACINGS", "GROWTH", "PROBE_MIN", "probe_grid", "fitted_side", "solve_in_window"]

#: The window's half side over the probe's contact reach (max |x|, |y| of a contact pixel).
MARGIN = 1.25
#: Asperity spacings 1/sqrt(eta) added to the window's half side beyond MARGIN x reach.
PAD_SPACINGS = 2.0
#: Factor by which a window that the contact reaches grows before the solve is repeated.
GROWTH = 1.5
#: Smallest probe grid (pixels along a side of the set's window): 35 um pixels on the GW default set.
PROBE_MIN = 128


def probe_grid(vset: scene.ValidationSet, ensemble: bool = False) -> int:
    """Pixels along a side of the probe grid of a case on the main grid (part 2's ``ensemble``
    cases: the ensemble grid): an eighth of it, at least :data:`PROBE_MIN` (at most the grid
    itself), and on the random-process surface at least two per shortest wavelength (the band
    on the grid). The probe only finds the contact's reach; the window's margins absorb its error."""
    grid = vset.ensemble_grid if ensemble else vset.n_grid
    n = min(grid, max(PROBE_MIN, grid // 8))
    if vset.surface == "random_process":
        n = max(n, math.ceil(2.0 * vset.side / vset.short_wavelength))
    return n


def fitted_side(vset: scene.ValidationSet, realization: int, force: float,
                ensemble: bool = False) -> tuple[float, float]:
    """The window side (m) of a case and the probe's contact reach (m) on the set's window
    (``ensemble``: part 2's probe, :func:`probe_grid`).

    Raises
    ------
    g2tom.reference.elastic.SolverFailure
        If the probe's contact solve fails.
    """
    n = probe_grid(vset, ensemble)
    pixel = vset.side / n
    operator = elastic.free_surface(n, pixel, vset.e_star, vset.device, vset.solver)
    state = contact_at_force(operator, scene.rough_sphere(vset, realization, n), force, hardness=vset.hardness)
    c = cell_centres(n, pixel)
    iy, ix = np.nonzero(state.contact)
    reach = float(max(np.abs(c[ix]).max(), np.abs(c[iy]).max())) + pixel  # to the far side of the pixel
    half = MARGIN * reach + PAD_SPACINGS / math.sqrt(vset.eta)
    return min(vset.side, 2.0 * half), reach


def solve_in_window(vset: scene.ValidationSet, realization: int, n: int, force: float,
                    side: float) -> tuple[elastic.FreeSurface, np.ndarray, ContactState, float]:
    """The contact at ``force`` on an ``n x n`` grid of a centred window of ``side`` (m), grown by
    :data:`GROWTH` while the contact reaches its edge; returns the operator, the heights, the
    state and the final side (m).

    Raises
    ------
    ContactReachesEdge
        If the contact reaches the edge of the set's own window.
    g2tom.reference.elastic.SolverFailure
        If the contact solve fails.
    """
    while True:
        operator = elastic.free_surface(n, side / n, vset.e_star, vset.device, vset.solver)
        heights = scene.rough_sphere(vset, realization, n, side)
        try:
            return operator, heights, contact_at_force(operator, heights, force, hardness=vset.hardness), side
        except ContactReachesEdge:
            if side >= vset.side:
                raise
            side = min(vset.side, GROWTH * side)
