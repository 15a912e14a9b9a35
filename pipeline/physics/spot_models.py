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

from pipeline.physics.asperity import area_fraction, asperity_integral
from pipeline.physics.spots import spot_areas, spot_radii

__all__ = ["DISCRETIZATIONS", "HEIGHTS_TAG", "expected_radius", "cell_radius", "heights", "asperity_radius"]

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
