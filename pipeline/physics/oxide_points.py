"""Oxide fields at arbitrary points: the continuous field where discrete spots lie.

A field is ``psi(x, y) = Re sum_k c_k exp(2 pi i (i x + j y) / L)`` over its band
(:mod:`g2tom.physics.oxide_field`). Placing the coefficients on a (j, i) table and scaling the
coordinates to ``2 pi x / L`` makes the sum a type-2 non-uniform FFT, which FINUFFT evaluates at
any points to a stated relative tolerance in about ``O(M log M + P w^2)`` (``M`` table entries,
``P`` points, ``w`` the spreading width) instead of the ``O(M P)`` of the direct sum
(:func:`g2tom.physics.oxide_field.field_at_points`, the slow reference). One call per field,
so a field's values never depend on which other fields or points share its task; one thread
per call (the cube runs one task per core, and at a few thousand points FINUFFT's threads
cost more than they save).
"""

from __future__ import annotations

import threading

import finufft
import numpy as np

from g2tom.physics.oxide_band import Band

__all__ = ["TOLERANCE", "values_at_points"]

#: Relative tolerance of the transform (FINUFFT's ``eps``): values within ~1e-12 of the direct sum.
TOLERANCE = 1e-12


def values_at_points(modes: Band, coeffs: np.ndarray, x: np.ndarray, y: np.ndarray,
                     tolerance: float = TOLERANCE) -> np.ndarray:
    """Values of fields at points ``(x, y)`` (m, from the window's centre).

    Parameters
    ----------
    modes
        The band of the fields.
    coeffs
        Complex coefficients, shape (..., modes.size): any leading shape of fields.
    x, y
        Point coordinates, m, broadcast together to the points' shape.
    tolerance
        Relative tolerance of the transform.

    Returns
    -------
    numpy.ndarray
        float64, shape ``coeffs.shape[:-1] + points' shape``.
    """
    coeffs = np.asarray(coeffs)
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    lead, shape = coeffs.shape[:-1], x.shape
    flat = coeffs.reshape(-1, coeffs.shape[-1])
    out = np.empty((flat.shape[0], x.size))
    if x.size:
        top = int(max(np.abs(modes.i).max(), modes.j.max()))
        size = 2 * top + 2  # FINUFFT's modes run over -size/2 .. size/2 - 1 along each axis
        scale = 2.0 * np.pi / modes.period
        px, py = _phases(scale, x.ravel()), _phases(scale, y.ravel())
        table = np.zeros((size, size), dtype=complex)  # [j + size/2, i + size/2]
        plan = _plan(size, tolerance)
        plan.setpts(py, px)
        for b, c in enumerate(flat):
            table[modes.j + size // 2, modes.i + size // 2] = c
            out[b] = plan.execute(table).real
    return out.reshape(lead + shape)


#: FINUFFT takes point phases in [-3 pi, 3 pi) and folds them itself (the field has the period L).
PHASE_LIMIT = 3.0 * np.pi


def _phases(scale: float, x: np.ndarray) -> np.ndarray:
    """``scale * x`` (rad), wrapped into [-pi, pi) only where some phase lies outside
    [-:data:`PHASE_LIMIT`, :data:`PHASE_LIMIT`): the points of a window inside one period never do,
    and wrapping them all cost ~15 % of a field's evaluation on the paper's pool (2 ms of 13 at
    lambda 1, 123k points)."""
    phase = scale * x
    if phase.size and (phase.min() < -PHASE_LIMIT or phase.max() >= PHASE_LIMIT):
        phase = np.remainder(phase + np.pi, 2.0 * np.pi) - np.pi
    return phase


_PLANS = threading.local()


def _plan(size: int, tolerance: float) -> finufft.Plan:
    """This thread's type-2 plan for a ``size`` x ``size`` table (kept: making one costs about
    as much as a transform of ten thousand points, and plans are not shared between threads).

    The points are not sorted (``spread_sort = 0``): the cube's come disc by disc, already close
    together, and a type-2 transform interpolates each point by itself, so the values are the
    same bit for bit; measured on the paper's pool in one process, the cube's time per map x0.94
    at lambda 1, x0.97 at 5 and 23."""
    plans = _PLANS.__dict__.setdefault("plans", {})
    if (size, tolerance) not in plans:
        plans[size, tolerance] = finufft.Plan(2, (size, size), eps=tolerance, isign=1, nthreads=1, spread_sort=0)
    return plans[size, tolerance]
