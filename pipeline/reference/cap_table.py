"""The capped cap's law, tabulated: ``F / F_c`` and ``a / a_c`` against ``w / omega_c``, with slopes.

The table of :mod:`g2tom.physics.cap_law`: nodes ``W = w / omega_c`` geometrically spaced from
the onset (``W = 1``) to ``top``, with the force and contact radius of the perfectly plastic
surface's cap there and their log-log slopes ``d ln F / d ln W`` and ``d ln a / d ln W``.

Each interior node is read off the solved family (:func:`g2tom.physics.capped_sphere.plastic_contact`,
a member per relative annulus width ``s``): five members about the node, spaced ``step`` in
``ln W``, each extrapolated from ``n`` and ``2 n`` annulus elements at the same ``s``
(Richardson, the error falling as ``n^-2``), and the quartic through their ``(ln W, ln F)`` and
``(ln W, ln a)`` gives the values and slopes at the node. Reading the family as a curve, rather
than solving at the node's own ``W``, keeps the rounding of a thin annulus's nodes out of the
table: it moves a member along the curve (``W`` by up to 2e-6 at ``W`` 40), not off it
(``F`` against ``W`` by 1e-15).

The ends are exact: Hertz's contact at the onset (1, 1, slopes 3/2 and 1/2; the capped law
leaves Hertz's as about ``(W - 1)^(5/2)``, so its slope is continuous there), and the uniform disc
at ``top`` (:func:`g2tom.physics.capped_sphere.uniform_disc_law`), which the capped law meets
exponentially fast: at ``W = 40`` the radius within 5e-9, the force within 1e-14.

``python -m g2tom.reference.cap_table`` prints the table as the constants of
:mod:`g2tom.physics.cap_law` (the defaults: 41 nodes to ``W = 40``, ``n = 128``, ``step = 0.01``).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from g2tom.physics.capped_sphere import (THINNEST_ANNULUS, critical_scales, plastic_contact, uniform_disc_law,
                                         uniform_disc_radius)

__all__ = ["cap_table"]

#: The unit cap: ``beta = 1`` m, ``E* = 1`` Pa, ``H = 2 / pi`` Pa make ``omega_c = a_c = 1`` m.
_UNIT_CAP = (1.0, 1.0, 2.0 / np.pi)
#: Annulus elements of the root search that places each node's members.
_SEARCH_ELEMENTS = 32


def _member(depth: float, n: int) -> np.ndarray:
    """``(ln W, ln(F / F_c), ln(a / a_c))`` of the family's member of annulus width ``exp(-depth)``."""
    omega_c, a_c, f_c = critical_scales(*_UNIT_CAP)
    contact = plastic_contact(np.exp(-depth), *_UNIT_CAP, n)
    return np.log([contact.interference / omega_c, contact.force / f_c, contact.radius / a_c])


def cap_table(nodes: int = 41, top: float = 40.0, n: int = 128, step: float = 0.01) -> dict[str, np.ndarray]:
    """The capped law at ``nodes`` geometrically spaced ``W = w / omega_c`` from 1 to ``top``.

    Parameters
    ----------
    nodes
        Number of nodes (>= 3).
    top
        The last node, ``w / omega_c``, in (1, 40] (the solve holds to about 47).
    n
        Annulus elements of the coarser solve (the finer has ``2 n``).
    step
        Spacing of the members read about each node, in ``ln W``.

    Returns
    -------
    dict of numpy.ndarray
        ``interference`` (``w / omega_c``), ``force`` (``F / F_c``), ``radius`` (``a / a_c``),
        ``force_slope`` and ``radius_slope`` (log-log slopes), each (nodes,), dimensionless.
    """
    if nodes < 3 or not 1.0 < top <= 40.0:
        raise ValueError(f"nodes = {nodes!r}, top = {top!r}: need nodes >= 3 and 1 < top <= 40")
    ratio = np.geomspace(1.0, top, nodes)
    force, radius = np.ones(nodes), np.ones(nodes)
    force_slope, radius_slope = np.full(nodes, 1.5), np.full(nodes, 0.5)
    deepest = -np.log(THINNEST_ANNULUS)
    for k in range(1, nodes - 1):
        target = np.log(ratio[k])
        depth = brentq(lambda d, t: _member(d, _SEARCH_ELEMENTS)[0] - t, 0.0, deepest, args=(target,), xtol=1e-10)
        rate = (_member(depth + 1e-3, _SEARCH_ELEMENTS)[0] - _member(depth - 1e-3, _SEARCH_ELEMENTS)[0]) / 2e-3
        members = np.array([(4.0 * _member(d, 2 * n) - _member(d, n)) / 3.0
                            for d in depth + step / rate * np.arange(-2, 3)])
        shift = (members[:, 0] - target) / step
        for column, value, slope in ((1, force, force_slope), (2, radius, radius_slope)):
            quartic = np.polynomial.polynomial.polyfit(shift, members[:, column], 4)
            value[k], slope[k] = np.exp(quartic[0]), quartic[1] / step
    x = float(uniform_disc_radius(top))
    force[-1], radius[-1] = float(uniform_disc_law(x)[1]), x
    radius_slope[-1] = top / (x * (x + 8.0 / np.pi**2))  # d ln x / d ln W on the uniform disc
    force_slope[-1] = 2.0 * radius_slope[-1]
    return {"interference": ratio, "force": force, "radius": radius, "force_slope": force_slope,
            "radius_slope": radius_slope}


def _constant(name: str, values: np.ndarray, width: int = 100) -> str:
    """``NAME = (v, v, ...)`` with every value to round-trip precision, wrapped at ``width`` columns."""
    lines, line = [], f"{name} = ("
    indent = " " * len(line)
    for k, value in enumerate(values):
        item = repr(float(value)) + (", " if k < len(values) - 1 else ")")
        if len(line) + len(item.rstrip()) > width:
            lines.append(line.rstrip())
            line = indent
        line += item
    return "\n".join(lines + [line])


if __name__ == "__main__":
    table = cap_table()
    for key, constant in (("interference", "CAP_INTERFERENCE"), ("force", "CAP_FORCE"), ("radius", "CAP_RADIUS"),
                          ("force_slope", "CAP_FORCE_SLOPE"), ("radius_slope", "CAP_RADIUS_SLOPE")):
        print(_constant(constant, table[key]))
