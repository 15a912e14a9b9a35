"""How a cell's share of the Greenwood–Tripp contact becomes a spot: three discretizations.

Within the Greenwood–Williamson model that Greenwood–Tripp averages, a cell of side
``dx = 1/sqrt(eta)`` holds on average one asperity; an asperity of height ``z`` above the
mean plane at separation ``h`` touches when ``z > h``, with interference ``d = z - h``, contact
radius ``sqrt(beta d)`` and area ``pi beta d``. With ``phi`` the N(0, sigma^2) height density
and ``F_n(h) = int_h^inf (z - h)^n phi(z) dz``:

``mean_area`` (the paper's Sect. 2.5.2)
    One spot carrying the cell's mean area ``A* dx^2 = pi beta F_1(h)``: radius
    ``sqrt(beta F_1(h))``. By Jensen's inequality it overstates the expected sum of radii by
    up to ``1 / sqrt(P(z > h))`` where few cells touch (13.5x at 39 N on the paper's scene),
    and breaks Barber's theorem accordingly.
``expected``
    One spot whose radius is the cell's expected sum of asperity radii,
    ``a = E[sqrt(beta (z - h)) ; z > h] = sqrt(beta) F_{1/2}(h)``. Its self-conductance
    ``2 a`` per cell times the cell area's density is ``2 eta sqrt(beta) F_{1/2}(h) =
    (-dp/dh) / E*``: the asperity layer's stiffness, so Barber's theorem holds asperity by
    asperity.
``asperities``
    One asperity per cell with a height ``z ~ N(0, sigma^2)`` drawn per realization and held
    over the load steps; radius ``sqrt(beta (z - h))`` where ``z > h``, else no spot. Its
    mean over realizations is the ``expected`` spot; the draws show the discreteness of light
    contacts (few spots, open circuits).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from g2tom.physics.asperity import area_fraction, asperity_integral
from g2tom.physics.spots import spot_areas, spot_radii

__all__ = ["DISCRETIZATIONS", "HEIGHTS_TAG", "expected_radius", "cell_radius", "heights", "asperity_radius",
           "nearest_cells", "placed_radius"]

#: The values of ``contact.spots``.
DISCRETIZATIONS = ("mean_area", "expected", "asperities")
#: Second entropy word of the asperity heights' streams: ``SeedSequence([seed, HEIGHTS_TAG],
#: spawn_key=(k,))`` for realization ``k``, never equal to an oxide field's stream
#: (``SeedSequence(seed, spawn_key=(lambda key, k))``), whose entropy is the seed alone.
HEIGHTS_TAG = 0x68676874  # "hght"


def expected_radius(h: ArrayLike, sigma: float, beta: float) -> np.ndarray:
    """Expected sum of asperity contact radii in a cell, ``sqrt(beta) F_{1/2}(h)``, m.

    Parameters
    ----------
    h
        Separation of the mean planes at the cell, m (any real value).
    sigma
        Standard deviation of asperity heights, m.
    beta
        Asperity tip radius, m.

    Returns
    -------
    numpy.ndarray
        Radii in m, shape of ``h``: positive, decreasing in ``h`` (underflowing to 0 only where
        the true value is below the smallest double).
    """
    return np.sqrt(beta) * asperity_integral(h, sigma, 0.5)


def cell_radius(h: ArrayLike, spots: str, sigma: float, eta: float, beta: float) -> np.ndarray:
    """The spot radius of a cell at separation ``h`` under the discretization ``spots``, m.

    ``mean_area``: ``sqrt(A*(h) dx^2 / pi)``; ``expected`` and ``asperities`` (whose mean over
    realizations it is): :func:`expected_radius`.

    Parameters
    ----------
    h
        Separation of the mean planes at the cell centres, m.
    spots
        One of :data:`DISCRETIZATIONS`.
    sigma, eta, beta
        Height std (m), asperity density (m^-2, the cell pitch is 1/sqrt(eta)), tip radius (m).

    Returns
    -------
    numpy.ndarray
        Radii, m, shape of ``h``.
    """
    if spots not in DISCRETIZATIONS:
        raise ValueError(f"spots = {spots!r} is not allowed: must be one of {', '.join(DISCRETIZATIONS)}")
    if spots == "mean_area":
        return spot_radii(spot_areas(area_fraction(h, sigma, eta, beta), 1.0 / np.sqrt(eta)))
    return expected_radius(h, sigma, beta)


def heights(seed: int, realization: int, n_cells: int, sigma: float) -> np.ndarray:
    """The asperity heights of one realization, one per cell, N(0, sigma^2), m.

    Realization ``k`` always gets the same heights (its own stream, independent of the oxide
    fields' streams and of which other realizations are drawn, in what batch or where).

    Parameters
    ----------
    seed
        The study's seed (``oxide.seed``).
    realization
        Realization index ``k >= 0``.
    n_cells
        Cells per side of the window.
    sigma
        Standard deviation of asperity heights, m.

    Returns
    -------
    numpy.ndarray
        Shape (n_cells, n_cells) as (y, x), float64, m.
    """
    stream = np.random.SeedSequence([seed, HEIGHTS_TAG], spawn_key=(int(realization),))
    return sigma * np.random.default_rng(stream).standard_normal((n_cells, n_cells))


def asperity_radius(z: ArrayLike, h: ArrayLike, beta: float) -> np.ndarray:
    """Contact radius ``sqrt(beta (z - h))`` of asperities of height ``z`` at separation ``h``, m.

    Parameters
    ----------
    z
        Asperity heights, m.
    h
        Separations of the mean planes, m, broadcastable against ``z``.
    beta
        Asperity tip radius, m.

    Returns
    -------
    numpy.ndarray
        Broadcast shape; 0 where the asperity does not touch (``z <= h``).
    """
    interference = np.asarray(z, float) - np.asarray(h, float)
    return np.sqrt(beta * np.maximum(interference, 0.0))


def nearest_cells(x: ArrayLike, y: ArrayLike, centres: np.ndarray) -> np.ndarray:
    """Flat index ``iy * n + ix`` of the cell whose centre is nearest to each point, or -1 outside the window.

    Parameters
    ----------
    x, y
        Point coordinates, m, same shape.
    centres
        The evenly spaced cell centres along one axis (the same for x and y), m, shape (n,).

    Returns
    -------
    numpy.ndarray
        int64, shape of ``x``; -1 where a point lies more than half a pitch beyond the outer centres.
    """
    pitch = centres[1] - centres[0]
    n = centres.size
    ix = np.rint((np.asarray(x, float) - centres[0]) / pitch).astype(np.int64)
    iy = np.rint((np.asarray(y, float) - centres[0]) / pitch).astype(np.int64)
    inside = (ix >= 0) & (ix < n) & (iy >= 0) & (iy < n)
    return np.where(inside, iy * n + ix, -1)


def placed_radius(z: ArrayLike, cells: np.ndarray, separation: np.ndarray, beta: float) -> np.ndarray:
    """Spot radii of given asperities placed in their cells: per cell, the sum of their contact radii, m.

    The discretization of a surface whose asperities are known (a GW surface's own tips): asperity
    ``j`` of height ``z_j`` in cell ``c_j`` touches where ``z_j > h(c_j)``, with radius
    ``sqrt(beta (z_j - h(c_j)))`` (:func:`asperity_radius`, at the separation of its cell's
    centre). A cell's spot carries the sum of its asperities' radii, so that its
    self-conductance ``2 a / rho*`` is the sum of theirs (their interaction within the cell is
    neglected, as in the ``expected`` spot, whose radius is this sum's expectation); a cell
    without a touching asperity has no spot.

    Parameters
    ----------
    z
        Asperity heights above the mean plane of heights, m, shape (m,).
    cells
        Flat cell index of each asperity (:func:`nearest_cells`), shape (m,); -1 drops it.
    separation
        Separations of the mean planes at the cell centres, m, shape (..., n, n).
    beta
        Asperity tip radius, m.

    Returns
    -------
    numpy.ndarray
        Radii, m, shape of ``separation``.
    """
    z = np.asarray(z, float)
    cells = np.asarray(cells, np.int64)
    if z.shape != cells.shape or z.ndim != 1:
        raise ValueError(f"z {z.shape} and cells {cells.shape} must be one-dimensional and of one length")
    h = np.asarray(separation, float)
    n_cells = h.shape[-2] * h.shape[-1]
    keep = cells >= 0
    if np.any(cells >= n_cells):
        raise ValueError(f"cell index {int(cells.max())} is beyond the {n_cells} cells of the separation map")
    flat = h.reshape(-1, n_cells)
    radii = asperity_radius(z[keep][None], flat[:, cells[keep]], beta)  # (maps, asperities)
    out = np.zeros_like(flat)
    for m in range(flat.shape[0]):
        out[m] = np.bincount(cells[keep], weights=radii[m], minlength=n_cells)
    return out.reshape(h.shape)
