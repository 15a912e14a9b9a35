"""The dimensionless groups mu and Pi of a rough sphere-on-flat contact.

With in-plane lengths in units of sqrt(R* sigma) and heights in units of sigma, the
Greenwood–Tripp problem depends on one group (Greenwood and Tripp's own),

    mu = (8/3) eta sigma sqrt(2 R* beta),

and the lattice of cells (pitch 1/sqrt(eta)) on a second,

    Pi = eta R* sigma        (cells per area R* sigma).

Spot radii in units of sqrt(R* sigma) scale with sqrt(beta / R*) = 3 mu / (8 sqrt(2) Pi).
With the oxide's xi and lambda (in cells) and F' = 2F / (E* sqrt(R* sigma^3)), the normalized
resistance R' = R sqrt(R* sigma) / (2 rho*) is a function of (xi, lambda, mu, Pi, F') alone;
E* and rho* only scale F and R. Table 1 (sigma 20 um, eta 2e8 m^-2, beta 30 um, R* 10 mm):
mu = 8.262, Pi = 40.

The inverse needs two of the four lengths-and-densities fixed: given sigma and R*,
eta = Pi / (R* sigma) and beta = (3 mu / (8 eta sigma))^2 / (2 R*).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Groups", "SurfaceScales", "greenwood_tripp_mu", "lattice_pi", "groups", "surface_from_groups"]


@dataclass(frozen=True)
class Groups:
    """The two groups of a scene.

    Attributes
    ----------
    mu
        Greenwood–Tripp's (8/3) eta sigma sqrt(2 R* beta), dimensionless.
    Pi
        Cells per area R* sigma, eta R* sigma, dimensionless.
    """

    mu: float
    Pi: float


@dataclass(frozen=True)
class SurfaceScales:
    """Asperity statistics and indenter radius of a scene, SI.

    Attributes
    ----------
    sigma
        Standard deviation of asperity heights, m.
    eta
        Asperity density, m^-2.
    beta
        Mean asperity tip radius, m.
    radius
        Effective radius R* of the sphere, m.
    """

    sigma: float
    eta: float
    beta: float
    radius: float


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} = {value!r} is out of range: must be a finite number > 0")
    return value


def greenwood_tripp_mu(sigma: float, eta: float, beta: float, radius: float) -> float:
    """mu = (8/3) eta sigma sqrt(2 R* beta), dimensionless.

    Parameters
    ----------
    sigma, eta, beta, radius
        Asperity height std (m), asperity density (m^-2), tip radius (m), sphere radius R* (m).
    """
    s, e, b, r = (_positive(n, v) for n, v in (("sigma", sigma), ("eta", eta), ("beta", beta), ("radius", radius)))
    return 8.0 / 3.0 * e * s * math.sqrt(2.0 * r * b)


def lattice_pi(sigma: float, eta: float, radius: float) -> float:
    """Pi = eta R* sigma, dimensionless: cells of area 1/eta per area R* sigma.

    Parameters
    ----------
    sigma, eta, radius
        Asperity height std (m), asperity density (m^-2), sphere radius R* (m).
    """
    s, e, r = (_positive(n, v) for n, v in (("sigma", sigma), ("eta", eta), ("radius", radius)))
    return e * r * s


def groups(sigma: float, eta: float, beta: float, radius: float) -> Groups:
    """(mu, Pi) of a surface and sphere (see :func:`greenwood_tripp_mu`, :func:`lattice_pi`)."""
    return Groups(mu=greenwood_tripp_mu(sigma, eta, beta, radius), Pi=lattice_pi(sigma, eta, radius))


def surface_from_groups(mu: float, Pi: float, sigma: float, radius: float) -> SurfaceScales:
    """The (sigma, eta, beta, R*) with groups (mu, Pi), given the reference lengths sigma and R*.

    Parameters
    ----------
    mu, Pi
        Target groups, > 0.
    sigma
        Asperity height std, m (sets the height scale).
    radius
        Sphere radius R*, m (with sigma, sets the in-plane scale sqrt(R* sigma)).

    Returns
    -------
    SurfaceScales
        eta = Pi / (R* sigma) and beta = (3 mu / (8 eta sigma))^2 / (2 R*).
    """
    mu, Pi = _positive("mu", mu), _positive("Pi", Pi)
    sigma, radius = _positive("sigma", sigma), _positive("radius", radius)
    eta = Pi / (radius * sigma)
    beta = (3.0 * mu / (8.0 * eta * sigma)) ** 2 / (2.0 * radius)
    return SurfaceScales(sigma=sigma, eta=eta, beta=beta, radius=radius)
