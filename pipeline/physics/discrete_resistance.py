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
(tests/test_discrete_resistance.py holds it against a direct solve of every set). Many layouts
(the realizations of a cube chunk) are solved by a few batched calls over padded unions
(:func:`layout_resistances`), each layout's answer bit-identical to solving it alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.linalg import lapack

__all__ = ["MODELS", "resistances", "layout_resistances", "bucket", "total_currents", "nested_order"]

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
    radius = np.asarray(radius, dtype=float)
    stacked = radius.reshape((radius.shape[0] if radius.ndim > 1 else 1, -1, radius.shape[-1]))
    return layout_resistances([kernel], [stacked], rho, model)[0].reshape(radius.shape[:-1])


def layout_resistances(kernels: Sequence[np.ndarray], radii: Sequence[np.ndarray], rho: float,
                       model: str = "point") -> list[np.ndarray]:
    """:func:`resistances` of many spot layouts (e.g. the realizations of a chunk), solved together.

    Parameters
    ----------
    kernels
        Per layout its coupling kernel, 1/m, shape (n, n) (n may differ between layouts).
    radii
        Per layout its radii, m, shape (sets, steps, n): the sets of a step (oxide fractions)
        share one factorization (:func:`total_currents`).
    rho
        Effective resistivity rho*, ohm m.
    model
        ``"point"`` or ``"greenwood"``.

    Returns
    -------
    list of numpy.ndarray
        Per layout the resistances in ohm, shape (sets, steps); ``inf`` where no spot conducts.

    Notes
    -----
    The point model gathers every (layout, step) onto its union of conducting spots in
    :func:`total_currents`'s order and pads it to a size of :func:`bucket` (zero-radius spots
    with no coupling), so the unions of a whole chunk are factorized by a few batched calls
    instead of one call per step. A union's padded size, and so every operation on it, depends
    on that union alone: the answer is bit-identical whichever other layouts share the call.
    """
    if model not in MODELS:
        raise ValueError(f"model = {model!r} is not allowed: must be one of {', '.join(MODELS)}")
    radii = [np.asarray(a, dtype=float) for a in radii]
    out = [np.full(a.shape[:2], np.inf) for a in radii]
    if model == "greenwood":
        for kernel, a, res in zip(kernels, radii, out):
            total = a.sum(axis=-1)
            quadratic = np.einsum("sdi,sdi->sd", a @ kernel, a)
            live = total > 0
            res[live] = rho * (total[live] / 2.0 + quadratic[live]) / total[live] ** 2
        return out
    groups: dict[int, list[tuple[int, np.ndarray, np.ndarray, np.ndarray]]] = {}
    for i, (kernel, a) in enumerate(zip(kernels, radii)):
        for size, steps, block, sets in _unions(kernel, a):
            groups.setdefault(size, []).append((i, steps, block, sets))
    for members in groups.values():
        currents = _ordered_total_currents(np.concatenate([m[2] for m in members]),
                                           np.concatenate([m[3] for m in members]))
        start = 0
        for i, steps, _, _ in members:
            part = currents[start:start + steps.size].T  # (sets, steps)
            start += steps.size
            with np.errstate(divide="ignore"):
                out[i][:, steps] = np.where(part > 0, rho / np.where(part > 0, part, 1.0), np.inf)
    return out


def bucket(size: np.ndarray) -> np.ndarray:
    """Padded size of a union of ``size`` spots: ``size`` up to 16, then rounded up to a multiple of
    an eighth of its octave's start (at most 12.5 % larger, so at most 1.42x the factorization's work)."""
    size = np.asarray(size, dtype=np.int64)
    octave = np.floor(np.log2(np.maximum(size, 16))).astype(np.int64)  # 4 up to 31, 5 up to 63, ...
    quantum = np.where(size > 16, 2 ** (octave - 3), 1)
    return -(-size // quantum) * quantum


def _unions(kernel: np.ndarray, a: np.ndarray):
    """Per padded size, the steps of one layout with a conducting spot, their unions' kernels and sets.

    Yields ``(size, steps, kernels (steps, size, size), radii (steps, sets, size))``: each step's
    union in :func:`nested_order`, padded by spots of radius 0 (their kernel entries are masked by
    :func:`_bordered_factor`).
    """
    sets, n_steps, n = a.shape
    conducting = a > 0
    union = conducting.any(axis=0)  # (steps, n)
    count = union.sum(axis=1)
    steps = np.flatnonzero(count)
    if steps.size == 0:
        return
    full = (a == a.max(axis=0)) & conducting
    order = np.argsort(np.where(union, -full.sum(axis=0), 1)[steps], axis=1, kind="stable")  # union first
    sizes = bucket(count[steps])
    width = int(sizes.max())
    if width > n:  # one spot with no coupling and radius 0 stands for every padding spot
        kernel = np.pad(kernel, ((0, 1), (0, 1)))
        a = np.pad(a, ((0, 0), (0, 0), (0, 1)))
        order = np.pad(order, ((0, 0), (0, width - n)), constant_values=n)
    for size in np.unique(sizes):
        chosen = sizes == size
        index = order[chosen, :size]
        block = kernel[index[:, :, None], index[:, None, :]]
        radii = np.take_along_axis(np.moveaxis(a[:, steps[chosen]], 0, 1), index[:, None, :], axis=2)
        yield int(size), steps[chosen], block, radii


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
    """``|z|^2 + b^T S^-1 b`` of every set (see :func:`total_currents`), shape (batch, sets).

    Each layout's partial sets are padded to the :func:`bucket` of its own widest one, so a
    layout's answer does not depend on the others in the batch.
    """
    n = a.shape[2]
    z = np.where(inside, lower[:, None, n, :n], 0.0)  # (batch, sets, n)
    total = np.einsum("bsn,bsn->bs", z, z)
    widths = np.minimum(bucket(rest.sum(axis=2).max(axis=1)), n)
    for width in np.unique(widths[widths > 0]):
        chosen = widths == width
        total[chosen] += _schur_part(lower[chosen], kernel[chosen], a[chosen], rest[chosen], inside[chosen],
                                     z[chosen], int(width))
    return total


def _schur_part(lower: np.ndarray, kernel: np.ndarray, a: np.ndarray, rest: np.ndarray, inside: np.ndarray,
                z: np.ndarray, width: int) -> np.ndarray:
    """``b^T S^-1 b`` of every set of layouts whose partial sets are padded to ``width``."""
    batch, n = a.shape[0], a.shape[2]
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
    return np.einsum("bsp,bsp->bs", b, np.linalg.solve(schur, b[..., None])[..., 0])


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
