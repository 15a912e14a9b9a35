"""One spherical cap on an elastic half-space whose contact pressure is capped by the hardness.

The *perfectly plastic surface*: a rigid paraboloid of tip radius ``beta`` pressed to the
interference ``w`` (displacement control) into the elastic half-space of effective modulus
``E*`` (both bodies), with the contact pressure bounded by the hardness ``H``. With ``u(r)`` the
surface displacement and ``g(r) = r^2 / (2 beta) - w + u(r)`` the gap, the box-constrained
contact problem is

    0 <= p <= H;   g = 0 where 0 < p < H;   g >= 0 where p = 0;   g <= 0 where p = H,

the surface being pushed in, as a yielded surface flows, where the pressure is at the hardness.
Only the surface pressure is bounded: it is not an elasto-plastic volume model.

Below the onset the contact is Hertz's: its peak pressure ``p0 = 2 E* a / (pi beta)`` reaches H
at ``a_c = pi beta H / (2 E*)``, ``omega_c = a_c^2 / beta``, ``F_c = pi^3 beta^2 H^3 / (6 E*^2)``
(:func:`critical_scales`). Above it the pressure is H on a central disc ``r < b``, between 0 and
H on the annulus ``b < r < a`` where the surfaces conform, and 0 outside. In the units
``(omega_c, a_c, F_c)`` the problem has no parameter left, so ``F / F_c`` and ``a / a_c``
against ``W = w / omega_c`` form one universal law (:func:`dimensionless_law`).

Solution on zones fitted to the contact (:func:`plastic_contact`). For a given relative width
``s = (a - b) / a`` of the annulus, radial nodes are laid out in units of ``a``: the annulus
with cosine spacing (crowded at both ends, where the pressure departs from H and from 0 as a
square root), the disc graded geometrically from the annulus's end element to the axis, and
an outer ring of zero pressure out to ``2 a`` where the gap is reported. The pressure is
piecewise linear on the nodes (:mod:`g2tom.physics.radial_grid`): H on the disc and at ``b``,
0 from ``a`` on, free at the annulus's inner nodes; the gap vanishes at every annulus node
``b .. a``. The displacement of the pressure on nodes ``a rho`` is ``a / a_c`` times that on
nodes ``a_c rho``, so the equations are linear in the free pressures, ``w / a`` and ``a`` itself:
one linear solve per ``s`` gives ``(w, F, a)``. The two equations in excess of the free
pressures, the gap's zero at the two ends where the pressure is held at H and at 0, are what
fix ``b`` and ``a``: they remove the inverse square root that a pressure otherwise has where
a prescribed displacement meets a prescribed pressure. Below the onset the disc is empty and
the pressure at the centre is free; the problem is then homogeneous (``p`` grows as ``a``,
``w`` as ``a^2``) and one solve at unit size, scaled, gives the contact at any ``w``.
Given ``w`` (:func:`capped_contact`), ``s`` is found by a root search on ``ln W`` along the
family, ``ln W`` being smooth and increasing in ``-ln s``.

Accuracy (measured; the error falls as ``n^-2`` with the annulus's ``n`` elements). Below the
onset, at the default ``n = 128``, the contact radius is 1.9e-5 above Hertz's and the force 8e-8
below it, at every interference (the problem is homogeneous there). Above it, against the
solve extrapolated from 128 and 256 elements (Richardson) at the same interference, the radius
is within 1.8e-5 just above the onset, 3e-6 at ``W = 2`` and 2e-7 from ``W = 5``, and the force
within 1e-7. The rounding of a thin annulus's nodes moves a member of the family along the law,
not off it: the interference met by :func:`capped_contact` is within 2e-8 of the one asked up
to ``W = 25`` and within 5e-6 beyond, and reported.

Far above the onset the annulus narrows as ``exp(-pi^2 a / (4 a_c))`` (the log-singular slope
of a uniformly loaded disc's displacement at its rim against the cap's slope ``a / beta``) and
the contact becomes the uniform disc of Holm's plastic spot, ``F = pi a^2 H``, at the
interference ``w = a^2 / (2 beta) + 4 H a / (pi E*)``, the rim displacement of that disc
(:func:`uniform_disc_law`). With ``s`` the annulus's relative width, the radius exceeds the
disc's (and Holm's ``sqrt(F / (pi H))``) by about ``s / 2``: 1.7e-4 at ``W = 10``, 3e-6 at 19,
8e-9 at 37.5; the force against the interference meets the disc's sooner, by about
``s^2 / 10`` (1e-8 at ``W = 10``). The solve is refused past ``s = 1e-9`` (``W`` about 47,
``F`` about 120 ``F_c``), where annulus elements narrower than ``1e-13 a`` would lose their
length to rounding and the uniform disc is exact to 5e-10.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from g2tom.physics.radial_grid import force_weights, influence_matrix

__all__ = [
    "CappedContact",
    "DEFAULT_ELEMENTS",
    "THINNEST_ANNULUS",
    "critical_scales",
    "uniform_disc_law",
    "uniform_disc_radius",
    "plastic_contact",
    "capped_contact",
    "dimensionless_law",
]

#: Elements across the annulus (across the whole contact below the onset); the graded disc
#: gets half as many and the outer ring a quarter.
DEFAULT_ELEMENTS = 128
#: The narrowest annulus solved, relative to the contact radius (see the module).
THINNEST_ANNULUS = 1e-9
#: The longest element integrated whole, relative to the radius of its inner node.
_SPLIT = 0.25
#: The root search's elements when it brackets the annulus width before the full solve.
_COARSE_ELEMENTS = 24


@dataclass(frozen=True)
class CappedContact:
    """One capped cap's contact at one interference.

    Attributes
    ----------
    interference
        Interference ``w``, m.
    force
        Total force, N.
    radius
        Contact radius ``a``, m.
    plastic_radius
        Radius ``b`` of the disc at the hardness, m (0 below the onset).
    r
        Radial nodes, m, from 0 to ``2 a``; the pressure is linear between them.
    pressure
        Pressure at the nodes, Pa (0 from ``a`` on).
    gap
        Gap ``r^2 / (2 beta) - w + u(r)`` at the nodes, m: zero on the annulus (on the whole
        contact below the onset), <= 0 on the plastic disc, >= 0 outside.
    """

    interference: float
    force: float
    radius: float
    plastic_radius: float
    r: np.ndarray
    pressure: np.ndarray
    gap: np.ndarray


def critical_scales(beta: float, e_star: float, hardness: float) -> tuple[float, float, float]:
    """The onset of the capped law: ``(omega_c, a_c, F_c)`` in m, m, N.

    Hertz's peak pressure ``2 E* a / (pi beta)`` reaches the hardness at ``a_c = pi beta H /
    (2 E*)``, the interference ``omega_c = a_c^2 / beta`` and the force ``F_c = pi^3 beta^2 H^3
    / (6 E*^2)``.

    Parameters
    ----------
    beta
        Cap (tip) radius, m, > 0.
    e_star
        Effective modulus E*, Pa, > 0.
    hardness
        Hardness H, Pa, > 0.
    """
    for name, value in (("beta", beta), ("e_star", e_star), ("hardness", hardness)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value!r} is out of range: must be > 0")
    a_c = np.pi * beta * hardness / (2.0 * e_star)
    return a_c * a_c / beta, a_c, np.pi**3 * beta**2 * hardness**3 / (6.0 * e_star**2)


def uniform_disc_law(x: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The capped law's far limit, the uniform disc of Holm's plastic spot, at ``x = a / a_c``.

    ``F = pi a^2 H`` at ``w = a^2 / (2 beta) + 4 H a / (pi E*)``: in units of the onset,
    ``w / omega_c = x^2 / 2 + 8 x / pi^2`` and ``F / F_c = 3 x^2 / 2``.

    Returns
    -------
    tuple of numpy.ndarray
        ``w / omega_c`` and ``F / F_c``, dimensionless, shaped like ``x``.
    """
    x = np.asarray(x, dtype=float)
    return 0.5 * x * x + 8.0 / np.pi**2 * x, 1.5 * x * x


def uniform_disc_radius(ratio: ArrayLike) -> np.ndarray:
    """The inverse of :func:`uniform_disc_law`: ``a / a_c`` of the uniform disc at ``w / omega_c = ratio``.

    The root of ``x^2 / 2 + 8 x / pi^2 = ratio``, written ``2 ratio / (c + sqrt(c^2 + 2 ratio))``
    with ``c = 8 / pi^2`` (no cancellation).
    """
    ratio = np.asarray(ratio, dtype=float)
    c = 8.0 / np.pi**2
    return 2.0 * ratio / (c + np.sqrt(c * c + 2.0 * ratio))


def _graded(length: float, first: float, count: int) -> np.ndarray:
    """``count + 1`` offsets from 0 to ``length`` whose elements grow geometrically from ``first``.

    The growth is ``exp(k / count)`` with ``k >= 0`` solved from the first element, so the
    offsets are smooth in ``length`` and ``first``; ``first >= length / count`` gives even
    elements.
    """
    from scipy.optimize import brentq  # here: every command imports this module through the cap laws

    share = first / length
    s = np.linspace(0.0, 1.0, count + 1)
    if share * count >= 1.0 - 1e-9:  # a grading below 1e-9: even (k would be below its bracket)
        return length * s

    def excess(k: float) -> float:
        return float(np.expm1(k / count) / np.expm1(k) - share)

    top = 2.0 * np.log(1.0 / share) / (1.0 - 1.0 / count) + 1.0
    k = brentq(excess, 1e-9, top, xtol=1e-14, rtol=1e-14)
    return length * np.expm1(k * s) / np.expm1(k)


def _nodes(width: float, n: int) -> tuple[np.ndarray, int, int]:
    """Nodes in units of the contact radius for the annulus width ``width`` = (a - b) / a.

    Returns the nodes (0 .. 2), the index of ``b`` and the index of ``a`` (the node 1).
    """
    b = 1.0 - width
    annulus = b + width * 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, n + 1)))
    annulus[-1] = 1.0
    end = annulus[1] - annulus[0]
    outer = 1.0 + _graded(1.0, end, max(n // 4, 2))
    if b <= 0.0:
        return np.concatenate([annulus, outer[1:]]), 0, n
    n_disc = max(n // 2, 2)
    disc = b - _graded(b, end * b / (n_disc * end + b), n_disc)[::-1]
    disc[0] = 0.0
    return np.concatenate([disc[:-1], annulus, outer[1:]]), n_disc, n_disc + n


def _scaled_matrix(rho: np.ndarray, a_c: float, e_star: float) -> np.ndarray:
    """The influence matrix on the nodes ``a_c rho`` in units of ``a_c / E*`` (dimensionless).

    The displacement kernel varies on the scale of the target's radius, and an element longer
    than a fraction :data:`_SPLIT` of its inner node's radius (near the axis, or next to a
    plastic disc far smaller than the annulus's first element) loses accuracy to it: such an
    element is integrated in pieces of one ratio, at most ``1 + _SPLIT``, of outer to inner
    radius, the pressure staying linear across it (the pieces' nodal values are interpolated).
    """
    inner, outer = rho[:-1], rho[1:]
    long = np.flatnonzero((inner > 0) & (outer - inner > _SPLIT * inner))
    if long.size == 0:
        return influence_matrix(a_c * rho, e_star) * (e_star / a_c)
    growth = np.log(outer[long] / inner[long])
    pieces = np.ceil(growth / np.log1p(_SPLIT)).astype(int)
    fine = np.union1d(rho, np.concatenate([r * np.exp(g * np.arange(1, m) / m)
                                           for r, g, m in zip(inner[long], growth, pieces)]))
    k = np.clip(np.searchsorted(rho, fine, side="right") - 1, 0, rho.size - 2)
    t = (fine - rho[k]) / (rho[k + 1] - rho[k])
    spread = np.zeros((fine.size, rho.size))  # the nodal values at the fine nodes, linear between rho's
    spread[np.arange(fine.size), k] = 1.0 - t
    spread[np.arange(fine.size), k + 1] += t
    rows = np.searchsorted(fine, rho)
    return influence_matrix(a_c * fine, e_star)[rows] @ spread * (e_star / a_c)


def plastic_contact(width: float, beta: float, e_star: float, hardness: float,
                    n: int = DEFAULT_ELEMENTS) -> CappedContact:
    """The capped contact above the onset whose annulus has the relative width ``width``.

    Parameters
    ----------
    width
        ``(a - b) / a`` in [:data:`THINNEST_ANNULUS`, 1] (1: the onset, no plastic disc).
    beta, e_star, hardness
        Cap radius (m), effective modulus (Pa) and hardness (Pa).
    n
        Elements across the annulus (>= 4).

    Returns
    -------
    CappedContact
        The contact, at the interference the width belongs to.
    """
    if not THINNEST_ANNULUS <= width <= 1.0:
        raise ValueError(f"width = {width!r} is out of range: must be in [{THINNEST_ANNULUS:g}, 1]")
    if n < 4:
        raise ValueError(f"n = {n!r} is out of range: must be >= 4")
    omega_c, a_c, _ = critical_scales(beta, e_star, hardness)
    rho, i_b, i_a = _nodes(width, n)
    matrix = _scaled_matrix(rho, a_c, e_star)
    rows = np.arange(i_b, i_a + 1)
    free = np.arange(i_b + 1, i_a)
    # (M p)_i - w / alpha + (alpha omega_c / 2) rho_i^2 = 0 on the annulus, alpha = a / a_c; in units
    # of H (pressure) and H a_c / E* (lengths)
    system = np.column_stack([matrix[np.ix_(rows, free)], -np.ones(rows.size), rho[rows] ** 2])
    solved = np.linalg.solve(system, -matrix[rows, : i_b + 1].sum(axis=1))
    share = np.zeros(rho.size)
    share[: i_b + 1] = 1.0
    share[free] = solved[:-2]
    reach, slope = solved[-2], solved[-1]  # w / alpha and alpha omega_c / 2, in units of H a_c / E*
    alpha = 2.0 * slope * hardness * a_c / (e_star * omega_c)
    return _contact(rho, share, alpha, reach, slope, matrix, i_b, beta, e_star, hardness)


def _contact(rho: np.ndarray, share: np.ndarray, alpha: float, reach: float, slope: float, matrix: np.ndarray,
             i_b: int, beta: float, e_star: float, hardness: float) -> CappedContact:
    """The contact in SI units from the solve's pressure share ``p / H`` at the nodes, ``alpha = a / a_c``
    and ``w / alpha``, ``alpha omega_c / 2`` in units of ``H a_c / E*``."""
    _, a_c, _ = critical_scales(beta, e_star, hardness)
    unit = hardness * a_c / e_star
    a = alpha * a_c
    r = a * rho
    pressure = hardness * share
    gap = alpha * unit * (slope * rho**2 - reach + matrix @ share)
    return CappedContact(interference=float(alpha * unit * reach), force=float(force_weights(r) @ pressure),
                         radius=float(a), plastic_radius=float(r[i_b]) if i_b > 0 else 0.0, r=r,
                         pressure=pressure, gap=gap)


def _elastic_contact(w: float, beta: float, e_star: float, hardness: float, n: int) -> CappedContact:
    """The contact of ``w`` without the cap (the pressure free at every node of the contact).

    Solved at ``a = a_c`` and scaled: ``p`` grows as ``a`` and ``w`` as ``a^2``. Its pressure
    exceeds the hardness when ``w`` lies above the (discrete) onset.
    """
    _, a_c, _ = critical_scales(beta, e_star, hardness)
    rho, _, i_a = _nodes(1.0, n)
    matrix = _scaled_matrix(rho, a_c, e_star)
    rows = np.arange(i_a + 1)
    # at alpha = 1 the parabola's term is (omega_c / 2) rho^2 = (pi / 4) rho^2 in units of H a_c / E*
    system = np.column_stack([matrix[np.ix_(rows, rows[:-1])], -np.ones(rows.size)])
    solved = np.linalg.solve(system, -np.pi / 4.0 * rho[rows] ** 2)
    alpha = np.sqrt(w / (solved[-1] * hardness * a_c / e_star))
    share = np.zeros(rho.size)
    share[:i_a] = alpha * solved[:-1]
    return _contact(rho, share, alpha, alpha * solved[-1], alpha * np.pi / 4.0, matrix, 0, beta, e_star, hardness)


def capped_contact(w: float, beta: float, e_star: float, hardness: float,
                   n: int = DEFAULT_ELEMENTS) -> CappedContact:
    """The contact of one cap pressed to the interference ``w`` on the perfectly plastic surface.

    Parameters
    ----------
    w
        Interference, m, > 0.
    beta
        Cap (tip) radius, m.
    e_star
        Effective modulus E*, Pa.
    hardness
        Hardness H, Pa (the pressure's bound).
    n
        Elements across the annulus (across the contact below the onset), >= 4.

    Returns
    -------
    CappedContact
        Force, contact radius, plastic radius and the pressure and gap profiles.

    Raises
    ------
    ValueError
        For ``w <= 0``, or ``w`` beyond the thinnest annulus solved (about 47 ``omega_c``), where
        the contact is the uniform disc (:func:`uniform_disc_law`) to better than 1e-9.

    Notes
    -----
    Below the onset one solve. Above it a root search along the family on ``ln W``: bracketed
    on 24 elements, then solved on ``n``; the interference met is reported (within 2e-8 of ``w``
    up to 25 ``omega_c``, 5e-6 beyond, where the family's members carry the rounding of a thin
    annulus's nodes along the law).
    """
    if not (np.isfinite(w) and w > 0):
        raise ValueError(f"w = {w!r} is out of range: must be > 0 (m)")
    if n < 4:
        raise ValueError(f"n = {n!r} is out of range: must be >= 4")
    elastic = _elastic_contact(w, beta, e_star, hardness, n)
    if elastic.pressure[0] <= hardness:
        return elastic
    omega_c = critical_scales(beta, e_star, hardness)[0]
    target = np.log(w / omega_c)
    from scipy.optimize import brentq  # here: every command imports this module through the cap laws

    top = -np.log(THINNEST_ANNULUS)

    def excess(depth: float, elements: int) -> float:
        return float(np.log(plastic_contact(np.exp(-depth), beta, e_star, hardness, elements).interference
                            / omega_c) - target)

    # the root on a coarse grid first, then a bracket about it on the full one
    if excess(0.0, _COARSE_ELEMENTS) >= 0.0:
        guess = 0.0
    elif excess(top, _COARSE_ELEMENTS) <= 0.0:
        guess = top
    else:
        guess = brentq(excess, 0.0, top, args=(_COARSE_ELEMENTS,), xtol=1e-6)
    step = 0.05
    low, high = max(guess - step, 0.0), min(guess + step, top)
    while low > 0.0 and excess(low, n) > 0.0:
        step *= 4.0
        low = max(guess - step, 0.0)
    while excess(high, n) < 0.0:
        if high == top:
            raise ValueError(f"w = {w!r} m is {w / omega_c:.4g} omega_c: beyond the thinnest annulus solved "
                             f"({THINNEST_ANNULUS:g} a), where the contact is the uniform disc")
        step *= 4.0
        high = min(guess + step, top)
    depth = brentq(excess, low, high, args=(n,), xtol=1e-8)  # ln W to about 1e-8
    return plastic_contact(np.exp(-depth), beta, e_star, hardness, n)


def dimensionless_law(ratio: float, n: int = DEFAULT_ELEMENTS) -> tuple[float, float]:
    """The capped law in the onset's units: ``w / omega_c`` -> ``(F / F_c, a / a_c)``.

    Solved by :func:`capped_contact` on the unit cap (``beta = 1`` m, ``E* = 1`` Pa, ``H = 2 / pi``
    Pa, so ``omega_c = a_c = 1`` m); any other cap gives the same numbers (universality). The
    values are those at the interference met (see :func:`capped_contact`).

    Parameters
    ----------
    ratio
        ``w / omega_c`` > 0.
    n
        Elements across the annulus.
    """
    beta, e_star, hardness = 1.0, 1.0, 2.0 / np.pi
    omega_c, a_c, f_c = critical_scales(beta, e_star, hardness)
    contact = capped_contact(ratio * omega_c, beta, e_star, hardness, n)
    return contact.force / f_c, contact.radius / a_c
