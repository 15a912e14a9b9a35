"""Resistance of discrete contact spots at arbitrary positions: the point-interaction solve and Greenwood's form.

Spots ``i`` of radius ``a_i`` at ``(x_i, y_i)`` all at one potential: the currents ``f`` solve
``M f = 1`` with ``M_ii = 1 / (2 a_i)`` and ``M_ij = 1 / (pi max(d_ij, l))`` (the coupling kernel
of :mod:`pipeline.physics.discrete_contact`, floor ``l`` included, so that Barber's theorem
``1 / R = K / (E* rho*)`` holds exactly for the clean contact), and ``R = rho* / sum f``.
Greenwood's closed form is the Rayleigh quotient of ``M`` at ``f`` proportional to ``a``:
``R_G = rho* (sum a / 2 + a^T K a) / (sum a)^2``, an upper bound on the point model's ``R``.
An oxide rule enters only through the radii (an effective radius ``a sqrt(f)``, or 0 for a spot
that does not conduct). No conducting spot: ``R = inf`` (an open circuit).

The oxide fractions of one load step are solved together by one factorization of the union of
their spots and a small Schur complement per fraction (:func:`total_currents`): exact, and
1.5x faster than a factorization per fraction on the paper's scene with nine fractions
(tests/test_discrete_resistance.py holds it against a direct solve of every set).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

__all__ = ["MODELS", "resistances", "total_currents", "nested_order"]

#: The resistance models on discrete spots.
MODELS = ("point", "greenwood")
#: Corner of a matrix bordered by ones, 1/m: above any ``1^T M^-1 1`` (m), so the bordered matrix
#: is positive definite with ``M`` and its factor's last row is ``L^-1 1``.
_CORNER = 1e300
#: Radius (m) standing for "not conducting" inside a batched factorization: ``M_ii = 1e300 / m``.
NEGLIGIBLE = 1e-300


def resistances(kernel: np.ndarray, radius: np.ndarray, rho: float, model: str = "point") -> np.ndarray:
    """Resistance of each set of spot radii on one set of positions.

    Parameters
    ----------
    kernel
        ``1 / (pi max(d_ij, l))`` of the positions, zero diagonal, 1/m, shape (n, n)
        (:func:`pipeline.physics.discrete_contact.interaction_kernel`).
    radius
        Spot radii, m, shape (..., n); 0 where a spot does not conduct. The point model solves
        the sets along the first axis together (e.g. the oxide fractions of one load step) by
        :func:`total_currents`.
    rho
        Effective resistivity rho*, ohm m.
    model
        ``"point"`` (exact solve) or ``"greenwood"`` (closed form).

    Returns
    -------
    numpy.ndarray
        Resistances in ohm, shape ``radius.shape[:-1]``; ``inf`` where no spot conducts.
    """
    if model not in MODELS:
        raise ValueError(f"model = {model!r} is not allowed: must be one of {', '.join(MODELS)}")
    radius = np.asarray(radius, dtype=float)
    total = radius.sum(axis=-1)
    out = np.full(total.shape, np.inf)
    live = total > 0
    if model == "greenwood":
        quadratic = np.einsum("...i,...i->...", radius @ kernel, radius)
        out[live] = rho * (total[live] / 2.0 + quadratic[live]) / total[live] ** 2
        return out
    stacked = radius.reshape((radius.shape[0] if radius.ndim > 1 else 1, -1, radius.shape[-1]))
    flat_out, flat_live = out.reshape(stacked.shape[:2]), live.reshape(stacked.shape[:2])
    for column in range(stacked.shape[1]):
        rows = np.flatnonzero(flat_live[:, column])
        if rows.size == 0:
            continue
        sets = stacked[rows, column]
        spots = np.flatnonzero((sets > 0).any(axis=0))
        spots = spots[nested_order(sets[None, :, spots])[0]]
        currents = _ordered_total_currents(kernel[np.ix_(spots, spots)][None], sets[None, :, spots])[0]
        flat_out[rows, column] = rho / currents
    return out


def total_currents(kernel: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``1^T f`` of ``M f = 1`` (the conductance over ``1 / rho*``, m) for batches of sets of radii.

    Parameters
    ----------
    kernel
        Coupling kernels, 1/m, shape (batch, n, n), zero diagonal (a batch of spot layouts, padded:
        a padding spot has radius 0 in every set and zero kernel entries).
    a
        Radii, m, shape (batch, sets, n); 0 where a spot does not conduct in a set. The sets of
        one layout differ only in their radii (the oxide fractions of one load step).

    Returns
    -------
    numpy.ndarray
        ``1^T M^-1 1`` over each set's conducting spots, m, shape (batch, sets); 0 where none conducts.

    Notes
    -----
    The sets of a layout share ``M``'s off-diagonal; with ``top`` each spot's largest radius
    over the sets, the union's ``U = K + diag(1 / (2 top))`` is factorized once, ``U = L L^T``,
    its spots ordered so that the spots a set keeps at their largest radius come first as far
    as they can (by the number of sets that keep them, most first: a prefix of every set when
    the sets are nested, as the oxide fractions of one field make them). A set's leading ``m``
    spots at full radius form a leading block of ``U``, factorized by ``L[:m, :m]``; its other
    conducting spots ``P`` (smaller radius, or full radius out of order) enter through the Schur
    complement:

        1^T M^-1 1 = |z|^2 + b^T S^-1 b,  z = (L^-1 1)[:m],
        G = L[P, :m],  S = M[P, P] - G G^T,  b = 1 - G z,

    exact in exact arithmetic (``G`` is ``(L[:m, :m]^-1 M[:m, P])^T``: a Cholesky factor's rows
    below a leading block). ``L^-1 1`` comes with the factor, as the last row of the factor of
    ``U`` bordered by ones. A layout whose ``P`` are so wide that factorizing every set by itself
    takes fewer operations (``n^3 / 3 + sets (p^2 n + p^3) > sets n^3 / 3``), or whose ``U`` is
    not positive definite (large caps closer than the coupling floor), has every set solved by
    itself (:func:`_whole_sets`).
    """
    a = np.asarray(a, dtype=float)
    order = nested_order(a)
    a = np.take_along_axis(a, order[:, None, :], axis=2)
    kernel = np.take_along_axis(np.take_along_axis(kernel, order[:, :, None], axis=1), order[:, None, :], axis=2)
    return _ordered_total_currents(kernel, a)


def nested_order(a: np.ndarray) -> np.ndarray:
    """The order of :func:`total_currents`'s factorization: spots by the number of sets that keep
    them at their largest radius, most first (stable), shape (batch, n) of radii (batch, sets, n)."""
    full = (a == a.max(axis=1, keepdims=True)) & (a > 0)
    return np.argsort(-full.sum(axis=1), axis=1, kind="stable")


def _ordered_total_currents(kernel: np.ndarray, a: np.ndarray) -> np.ndarray:
    """:func:`total_currents` of layouts already in :func:`nested_order`."""
    batch, sets, n = a.shape
    top = a.max(axis=1)
    full = (a == top[:, None, :]) & (a > 0)
    inside = np.arange(n) < np.cumprod(full, axis=2).sum(axis=2)[..., None]  # (batch, sets, n)
    rest = (a > 0) & ~inside
    width = rest.sum(axis=2).max(axis=1)  # (batch,)
    nested = n ** 3 / 3 + sets * (width * width * n + width ** 3) <= sets * n ** 3 / 3
    nested = slice(None) if nested.all() else nested  # a view in the rule
    lower = _bordered_factor(kernel[nested], top[nested])
    factored = np.isfinite(lower[:, n, n])
    definite = np.zeros(batch, bool)
    definite[nested] = factored
    if definite.all():  # the rule: no copies
        return _schur_sums(lower, kernel, a, inside, rest)
    out = np.zeros((batch, sets))
    out[~definite] = _whole_sets(kernel[~definite], a[~definite])
    if definite.any():
        out[definite] = _schur_sums(lower[factored], kernel[definite], a[definite], inside[definite], rest[definite])
    return out


def _bordered_factor(kernel: np.ndarray, top: np.ndarray) -> np.ndarray:
    """Cholesky factors (batch, n + 1, n + 1) of the unions ``U = K + diag(1 / (2 top))`` bordered by ones.

    The last row holds ``L^-1 1`` (over the spots with ``top > 0``; the others get an identity
    row). A ``U`` that is not positive definite gets a factor of NaN.
    """
    live = top > 0
    if not live.all():
        kernel = kernel * (live[:, :, None] & live[:, None, :])
    return _factor_definite(_bordered(kernel, 1.0 / (2.0 * np.where(live, top, 0.5)), live))


def _bordered(kernel: np.ndarray, diagonal: np.ndarray, border: np.ndarray) -> np.ndarray:
    """``[[K + diag(d), e], [e^T, _CORNER]]``: kernels (..., n, n) with ``diagonal`` (..., n) on
    their diagonal, bordered by ``border`` (..., n; ones where a spot conducts)."""
    n = diagonal.shape[-1]
    out = np.zeros(diagonal.shape[:-1] + (n + 1, n + 1))
    out[..., :n, :n] = kernel
    out[..., np.arange(n), np.arange(n)] = diagonal
    out[..., n, :n] = out[..., :n, n] = border
    out[..., n, n] = _CORNER
    return out


def _factor_definite(matrices: np.ndarray) -> np.ndarray:
    """Lower Cholesky factors of a batch of symmetric matrices, in place; NaN for those not positive definite.

    One LAPACK ``potrf`` per matrix (as fast as NumPy's batched call, which fails the whole
    batch for one indefinite matrix), on the transposed view: the upper factor of ``M^T = M`` in
    Fortran order is the lower one in C order, so nothing is copied.
    """
    for matrix in matrices:
        _, info = lapack.dpotrf(matrix.T, lower=0, overwrite_a=1, clean=1)
        if info != 0:
            matrix[:] = np.nan
    return matrices


def _schur_sums(lower: np.ndarray, kernel: np.ndarray, a: np.ndarray, inside: np.ndarray,
                rest: np.ndarray) -> np.ndarray:
    """``|z|^2 + b^T S^-1 b`` of every set (see :func:`total_currents`), shape (batch, sets)."""
    batch, n = a.shape[0], a.shape[2]
    z = np.where(inside, lower[:, None, n, :n], 0.0)  # (batch, sets, n)
    total = np.einsum("bsn,bsn->bs", z, z)
    width = int(rest.sum(axis=2).max())
    if width == 0:
        return total
    # every set's P, padded to ``width`` by spots it does not use (an identity block, b = 0 there)
    rank = np.argsort(~rest, axis=2, kind="stable")[..., :width]  # (batch, sets, width)
    used = np.take_along_axis(rest, rank, axis=2)
    layout = np.arange(batch)[:, None, None]
    g = lower[layout, rank, :n] * inside[:, :, None, :]  # (batch, sets, width, n)
    block = kernel[layout[..., None], rank[..., :, None], rank[..., None, :]]
    own = np.take_along_axis(a, rank, axis=2)
    diagonal = np.arange(width)
    block[..., diagonal, diagonal] = 1.0 / (2.0 * np.where(used, own, 1.0))
    schur = np.where(used[..., :, None] & used[..., None, :], block - g @ np.swapaxes(g, -1, -2), 0.0)
    schur[..., diagonal, diagonal] += ~used
    b = np.where(used, 1.0 - np.einsum("bspn,bsn->bsp", g, z), 0.0)
    return total + np.einsum("bsp,bsp->bs", b, np.linalg.solve(schur, b[..., None])[..., 0])


def _whole_sets(kernel: np.ndarray, a: np.ndarray) -> np.ndarray:
    """:func:`total_currents` with every set solved by itself.

    Each set's ``M`` on all ``n`` spots, bordered by ones, is factorized (``1^T M^-1 1`` is the
    squared last row of the factor, as in :func:`_bordered_factor`), the sets of a layout in
    one batched call; a spot that does not conduct in a set gets ``M_ii = 1 / NEGLIGIBLE``
    there (its row of the factor is ``sqrt(M_ii)`` on the diagonal and below 1e-140 elsewhere,
    so the last row's sum of squares equals the solve without it to rounding). Where a set's
    ``M`` is not positive definite (large caps closer than the coupling floor), its conducting
    spots are solved by LU.
    """
    batch, sets, n = a.shape
    out = np.zeros((batch, sets))
    conducting = a > 0
    diagonal = np.where(conducting, 1.0 / (2.0 * np.where(conducting, a, 1.0)), 1.0 / NEGLIGIBLE)
    for b in range(batch):
        try:
            lower = np.linalg.cholesky(_bordered(kernel[b], diagonal[b], conducting[b]))
            out[b] = np.einsum("sn,sn->s", lower[:, n, :n], lower[:, n, :n])
            continue
        except np.linalg.LinAlgError:
            pass
        for s in np.flatnonzero(conducting[b].any(axis=1)):
            spots = np.flatnonzero(conducting[b, s])
            matrix = kernel[b][np.ix_(spots, spots)]
            matrix[np.arange(spots.size), np.arange(spots.size)] = 1.0 / (2.0 * a[b, s, spots])
            out[b, s] = np.linalg.solve(matrix, np.ones(spots.size)).sum()
    return out
