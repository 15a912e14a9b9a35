"""The square lattice's missing self-interaction: the constant C of the point model's lattice term.

A field of spots on a square lattice of pitch dx stands for a continuous distribution of
current, one cell's worth per spot. The interaction of spot ``i`` with the others, the lattice
sum ``sum_{j != i} f_j / (pi d_ij)``, misses the continuum's contribution of spot ``i``'s own
neighbourhood; for a smooth current density the difference is ``f_i C / (pi dx)`` with

    C = lim_{N -> inf} [ integral over S_N of dA / |r|  -  sum_{j in S_N, j != 0} 1 / |j| ],

lengths in units of dx, S_N the square of the (2N + 1)^2 cells centred on the lattice points
|j_x|, |j_y| <= N (half-side s = N + 1/2). Adding ``C / (pi dx)`` to the diagonal ``M_ii``
restores it. The integral over the square is 8 s ln(1 + sqrt 2); the difference then
converges as ``C - c_1 / s - c_3 / s^3 - ...`` (each cell contributes its cell average minus its
centre value, a smooth function of order r^-3 whose sum outside S_N has an expansion in odd
powers of 1/s), so :func:`lattice_constant` extrapolates it in 1/s (Richardson, by a linear
solve). The result is the analytic continuation of the lattice sum, C = -4 zeta(1/2) beta(1/2),
with Riemann's zeta and Dirichlet's beta (the tests check both).
"""

from __future__ import annotations

import numpy as np

__all__ = ["SQUARE_LATTICE_CONSTANT", "lattice_constant", "square_partial"]

#: C of the square lattice, dimensionless (:func:`lattice_constant`; = -4 zeta(1/2) beta(1/2)).
SQUARE_LATTICE_CONSTANT = 3.900264920001956


def square_partial(n: int) -> float:
    """The bracket of the definition of C on the square of (2n + 1)^2 cells (dimensionless).

    Parameters
    ----------
    n
        Lattice points per half-side (>= 1).

    Returns
    -------
    float
        8 s ln(1 + sqrt 2) - sum_{0 < max(|j_x|, |j_y|) <= n} 1 / |j|, s = n + 1/2.
    """
    if n < 1:
        raise ValueError(f"n = {n!r} is out of range: must be >= 1")
    k = np.arange(1, n + 1, dtype=float)
    off_axis = np.sum(1.0 / np.hypot(k[:, None], k[None, :]))  # one quadrant, both j_x, j_y > 0
    lattice = 4.0 * np.sum(1.0 / k) + 4.0 * off_axis
    return 8.0 * (n + 0.5) * np.log1p(np.sqrt(2.0)) - lattice


def lattice_constant(sizes: tuple[int, ...] = (16, 32, 64, 128)) -> float:
    """C by Richardson extrapolation of :func:`square_partial` in 1/s over the given sizes.

    With m sizes, the partial values are fitted exactly by C + sum_{i < m - 1} c_i s^-(2i + 1);
    with the default sizes the result agrees with -4 zeta(1/2) beta(1/2) to about 1e-13.

    Parameters
    ----------
    sizes
        Half-sides n of the squares (>= 2 distinct values, each >= 1).

    Returns
    -------
    float
        C, dimensionless.
    """
    n = np.asarray(sizes, dtype=float)
    if n.size < 2 or np.unique(n).size != n.size:
        raise ValueError(f"sizes = {sizes!r} must hold at least two distinct half-sides")
    s = n + 0.5
    basis = np.column_stack([np.ones_like(s)] + [s ** -(2 * i + 1) for i in range(s.size - 1)])
    values = np.array([square_partial(int(k)) for k in sizes])
    return float(np.linalg.solve(basis, values)[0])
