"""Resistance of discrete contact spots at arbitrary positions: the point-interaction solve and Greenwood's form.

Spots ``i`` of radius ``a_i`` at ``(x_i, y_i)`` all at one potential: the currents ``f`` solve
``M f = 1`` with ``M_ii = 1 / (2 a_i)`` and ``M_ij = 1 / (pi max(d_ij, l))`` (the coupling kernel
of :mod:`g2tom.physics.discrete_contact`, floor ``l`` included, so that Barber's theorem
``1 / R = K / (E* rho*)`` holds exactly for the clean contact), and ``R = rho* / sum f``.
Greenwood's closed form is the Rayleigh quotient of ``M`` at ``f`` proportional to ``a``:
``R_G = rho* (sum a / 2 + a^T K a) / (sum a)^2``, an upper bound on the point model's ``R``.
An oxide rule enters only through the radii (an effective radius ``a sqrt(f)``, or 0 for a spot
that does not conduct). No conducting spot: ``R = inf`` (an open circuit).

The sets of one load step (its oxide fractions) share ``M``'s off-diagonal. With ``top`` each
spot's largest radius over the sets, the union's ``U = K + diag(1 / (2 top))`` is factorized
once, ``U = L L^T``, its spots ordered so that the spots a set keeps at their largest radius
come first as far as they can (by the number of sets that keep them, most first: a prefix of
every set when the sets are nested, as the oxide fractions of one field make them). A set's
leading ``m`` spots at full radius form a leading block of ``U``, factorized by ``L[:m, :m]``;
its other conducting spots ``P`` (smaller radius, or full radius out of order) enter through the
Schur complement::

    1^T M^-1 1 = |z|^2 + b^T S^-1 b,  z = (L^-1 1)[:m],
    G = L[P, :m],  S = M[P, P] - G G^T,  b = 1 - G z,

exact in exact arithmetic (``G`` is ``(L[:m, :m]^-1 M[:m, P])^T``: a Cholesky factor's rows
below a leading block). ``L^-1 1`` comes with the factor, as the last row of the factor of ``U``
bordered by ones (corner :data:`CORNER`). A step whose partial sets are so wide that
factorizing every set by itself takes fewer operations (``m^3 / 3 + sum_s (p_s^2 m + p_s^3) >
sum_s c_s^3 / 3``, ``c_s`` the set's conducting spots) has every set solved by itself (Cholesky).

Large caps closer than the coupling floor (flattened capped caps) can leave ``U`` indefinite.
Then the same Schur complements run on its signed factor ``U = L D L^T``, ``D = diag(+-1)``
(Cholesky without pivoting, each negative pivot's sign kept), with ``|z|^2`` and ``G G^T``
weighted by ``D``. Without pivoting a small pivot would amplify rounding, so the factorization
gives up at a pivot below :data:`SIGNED_PIVOT_FLOOR` of its diagonal entry, and then every set
is solved by itself: Cholesky, its signed factor, or LU with partial pivoting.

The loops are compiled (numba, ``nogil``: the cube's dask threads run them side by side), one
surface at a time, so a realization's answer never depends on the chunk it is computed in.
Measured on the paper's pool (pickled layouts of 112 realizations, process time, one thread):
1.0-5.7 ms per realization with nine oxide fractions open (lambda 23 ... 1), 0.04-0.2 ms with
one, against 6.4-15 ms and 0.5-1.2 ms for the same algorithm in batched NumPy.
tests/test_discrete_resistance.py holds every path against a direct LU solve of every set.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["MODELS", "CORNER", "SIGNED_PIVOT_FLOOR", "resistances", "currents"]

#: The resistance models on discrete spots.
MODELS = ("point", "greenwood")
#: Corner of a matrix bordered by ones, 1/m: above any ``1^T M^-1 1`` (m), so the bordered matrix
#: is positive definite with ``M`` and its factor's last row is ``L^-1 1``.
CORNER = 1e300

#: Paths of :func:`currents` per step: no spot conducts; one union factorization and Schur
#: complements; every set by itself (wide partial sets); every set by itself (indefinite union);
#: conjugate gradients on every set at once (large unions); one signed factorization of an
#: indefinite union and Schur complements.
NONE, NESTED, WHOLE, INDEFINITE, ITERATIVE, SIGNED = 0, 1, 2, 3, 4, 5
#: A signed factorization (Cholesky without pivoting, ``L D L^T``) gives up at a pivot smaller than
#: this share of its diagonal entry: without pivoting, a small pivot would amplify rounding by about
#: its inverse. Then the step (or set) is solved by LU with partial pivoting instead.
SIGNED_PIVOT_FLOOR = 1e-3

#: Union size from which a step's sets are solved by conjugate gradients (``_iterative``)
#: rather than factorized: O(m^2) a sweep against O(m^3). Measured on the atlas's d22 scene
#: (mu 7.07, Pi 320, up to 1,990 touching spots, five oxide fractions, lambda 1 and 23): the
#: preconditioned condition number stays near 10 and 16 sweeps reach the tolerance; with 5 sets the
#: sweeps overtake the factorizations above a union of about ITERATIVE_FROM spots.
ITERATIVE_FROM = 400
#: Conjugate gradients stop on every set at ``|M f - 1| <= ITERATIVE_TOLERANCE |1|`` (2-norms), so
#: ``1^T f`` is within ~cond(M) times that of the exact solve; cond(M) preconditioned was <= 11.
ITERATIVE_TOLERANCE = 1e-11
#: Sweeps after which conjugate gradients give up and the step is factorized instead.
ITERATIVE_MAX_SWEEPS = 300


def resistances(kernel: np.ndarray, radius: np.ndarray, rho: float, model: str = "point") -> np.ndarray:
    """Resistance of each set of spot radii on one set of positions.

    Parameters
    ----------
    kernel
        ``1 / (pi max(d_ij, l))`` of the positions, zero diagonal, 1/m, shape (n, n)
        (:func:`g2tom.physics.discrete_contact.interaction_kernel`).
    radius
        Spot radii, m, shape (..., n); 0 where a spot does not conduct. The point model solves
        the sets along the first axis together (e.g. the oxide fractions of one load step; the
        axes between are load steps) by one factorization of their union.
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
    if model == "greenwood":
        total = radius.sum(axis=-1)
        quadratic = np.einsum("...i,...i->...", radius @ kernel, radius)
    else:
        sets = radius.reshape((radius.shape[0] if radius.ndim > 1 else 1, -1, radius.shape[-1]))
        total = currents(kernel, sets)[0].reshape(radius.shape[:-1])
    out = np.full(total.shape, np.inf)
    live = total > 0
    if model == "greenwood":
        out[live] = rho * (total[live] / 2.0 + quadratic[live]) / total[live] ** 2
    else:
        out[live] = rho / total[live]
    return out


def currents(kernel: np.ndarray, radius: np.ndarray,
             iterative_from: int = ITERATIVE_FROM) -> tuple[np.ndarray, np.ndarray]:
    """``1^T f`` of ``M f = 1`` (the conductance over ``1 / rho*``, m) of every set of every step.

    Parameters
    ----------
    kernel
        Coupling kernel, 1/m, shape (n, n), zero diagonal.
    radius
        Radii, m, shape (sets, steps, n); 0 where a spot does not conduct.
    iterative_from
        Union size (conducting spots of a step, any set) from which the step is solved by
        conjugate gradients (default ``ITERATIVE_FROM``; the factorizations below it).

    Returns
    -------
    tuple of numpy.ndarray
        ``1^T M^-1 1`` over each set's conducting spots, m, shape (sets, steps) (0 where none
        conducts), and the path each step took, shape (steps,): ``NONE``, ``NESTED``,
        ``WHOLE``, ``INDEFINITE``, ``ITERATIVE`` or ``SIGNED``.
    """
    kernel = np.ascontiguousarray(kernel, dtype=np.float64)
    radius = np.ascontiguousarray(radius, dtype=np.float64)
    if radius.ndim != 3 or kernel.shape != (radius.shape[2],) * 2:
        raise ValueError(f"kernel {kernel.shape} and radius {radius.shape} must be (n, n) and (sets, steps, n)")
    return _currents(kernel, radius, int(iterative_from))


@numba.njit(cache=True, nogil=True)
def _currents(kernel: np.ndarray, a: np.ndarray, iterative_from: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`currents`, compiled."""
    sets, steps, n = a.shape
    out = np.zeros((sets, steps))
    path = np.zeros(steps, np.int64)
    for d in range(steps):
        path[d] = _step(kernel, a[:, d, :], out[:, d], iterative_from)
    return out, path


@numba.njit(cache=True, nogil=True)
def _step(kernel: np.ndarray, a: np.ndarray, out: np.ndarray, iterative_from: int) -> int:
    """The sets (rows of ``a``, (sets, n)) of one step into ``out`` (sets,); returns the path."""
    sets, n = a.shape
    top = np.zeros(n)
    keep = np.zeros(n, np.int64)  # sets that keep the spot at its largest radius
    for i in range(n):
        for s in range(sets):
            top[i] = max(top[i], a[s, i])
        for s in range(sets):
            keep[i] += top[i] > 0.0 and a[s, i] == top[i]
    union = np.flatnonzero(top > 0.0)
    m = union.size
    if m == 0:
        return NONE
    if m >= iterative_from and _iterative(kernel, a, union, out):
        return ITERATIVE
    union = union[np.argsort(-keep[union], kind="mergesort")]  # stable: most kept first
    inside = np.zeros(sets, np.int64)  # the leading spots a set keeps at full radius
    width = np.zeros(sets, np.int64)  # its other conducting spots
    alone = 0.0
    for s in range(sets):
        k = 0
        while k < m and a[s, union[k]] == top[union[k]]:
            k += 1
        inside[s] = k
        count = k
        for q in range(k, m):
            count += a[s, union[q]] > 0.0
        width[s] = count - k
        alone += count ** 3 / 3.0
    shared = m ** 3 / 3.0
    for s in range(sets):
        shared += width[s] ** 2 * m + width[s] ** 3
    if shared <= alone:
        factor = _bordered(kernel, top, union)
        signs = np.ones(m + 1)
        path = NESTED
        if not _cholesky(factor, m + 1):  # an indefinite union: its signed factor, or every set alone
            factor = _bordered(kernel, top, union)
            path = SIGNED if _signed_cholesky(factor, m + 1, signs) else INDEFINITE
        if path != INDEFINITE:
            for s in range(sets):
                total, ok = _schur_total(kernel, a[s], union, factor, signs, inside[s], width[s])
                out[s] = total if ok else _set_total(kernel, a[s], union)[0]
            return path
    definite = True
    for s in range(sets):
        total, ok = _set_total(kernel, a[s], union)
        out[s] = total
        definite = definite and ok
    return WHOLE if definite else INDEFINITE


@numba.njit(cache=True, nogil=True)
def _iterative(kernel: np.ndarray, a: np.ndarray, union: np.ndarray, out: np.ndarray) -> bool:
    """``1^T M^-1 1`` of every set (rows of ``a``) into ``out`` by conjugate gradients, all sets at once.

    Every set's ``M`` (its conducting spots) is applied on the whole union, ``M p = c (K_u (c p))
    + d p`` with ``c`` the set's conducting mask and ``d = 1 / (2 a)`` (0 off it), so one product
    of the union's kernel ``K_u`` with the sets' directions (BLAS) serves every set a sweep; each
    set is preconditioned by its diagonal (Jacobi) and stops at :data:`ITERATIVE_TOLERANCE`.
    ``False`` (``out`` then unspecified) where a set meets a direction of non-positive curvature
    (``M`` not positive definite) or does not converge in :data:`ITERATIVE_MAX_SWEEPS` sweeps.
    """
    sets, m = a.shape[0], union.size
    coupling = np.empty((m, m))
    for p in range(m):
        for q in range(m):
            coupling[p, q] = kernel[union[p], union[q]]
    inverse = np.zeros((m, sets))  # the preconditioner, 2 a on conducting spots
    solution = np.zeros((m, sets))
    residual = np.zeros((m, sets))
    direction = np.zeros((m, sets))
    rz = np.zeros(sets)
    goal = np.zeros(sets)
    running = np.zeros(sets, np.bool_)
    for s in range(sets):
        count = 0
        for p in range(m):
            radius = a[s, union[p]]
            if radius > 0.0:
                inverse[p, s] = 2.0 * radius
                residual[p, s] = 1.0
                direction[p, s] = inverse[p, s]
                rz[s] += inverse[p, s]
                count += 1
        goal[s] = ITERATIVE_TOLERANCE * np.sqrt(count)
        running[s] = count > 0
    for _ in range(ITERATIVE_MAX_SWEEPS):
        if not running.any():
            for s in range(sets):
                out[s] = solution[:, s].sum()
            return True
        product = np.dot(coupling, direction)
        for s in range(sets):
            if not running[s]:
                continue
            curvature = 0.0
            for p in range(m):
                if inverse[p, s] > 0.0:
                    product[p, s] += direction[p, s] / inverse[p, s]
                else:
                    product[p, s] = 0.0
                curvature += direction[p, s] * product[p, s]
            if not curvature > 0.0:
                return False
            step = rz[s] / curvature
            norm = 0.0
            for p in range(m):
                solution[p, s] += step * direction[p, s]
                residual[p, s] -= step * product[p, s]
                norm += residual[p, s] ** 2
            if np.sqrt(norm) <= goal[s]:
                running[s] = False
                for p in range(m):
                    direction[p, s] = 0.0
                continue
            updated = 0.0
            for p in range(m):
                updated += residual[p, s] ** 2 * inverse[p, s]
            ratio = updated / rz[s]
            rz[s] = updated
            for p in range(m):
                direction[p, s] = inverse[p, s] * residual[p, s] + ratio * direction[p, s]
    return False


@numba.njit(cache=True, nogil=True)
def _schur_total(kernel: np.ndarray, a: np.ndarray, union: np.ndarray, factor: np.ndarray, signs: np.ndarray,
                 inside: int, width: int) -> tuple[float, bool]:
    """``z^T D z + b^T S^-1 b`` of one set (radii ``a``) from the union's bordered factor ``U = L D L^T``
    (``D = diag(signs)``, all ones for a Cholesky factor): ``z`` the border's row of ``L``,
    ``S = M[P, P] - G D G^T``, ``b = 1 - G D z``. ``False`` where ``S`` has no factor either (the set
    is then solved alone)."""
    m = union.size
    total = 0.0
    for k in range(inside):
        total += signs[k] * factor[m, k] ** 2
    if width == 0:
        return total, True
    rest = np.empty(width, np.int64)  # positions in the union's order
    j = 0
    for q in range(inside, m):
        if a[union[q]] > 0.0:
            rest[j] = q
            j += 1
    schur = np.empty((width + 1, width + 1))  # S bordered by b, corner CORNER
    for x in range(width):
        px = rest[x]
        b = 1.0
        for k in range(inside):
            b -= factor[px, k] * factor[m, k] * signs[k]
        schur[width, x] = b
        for y in range(x + 1):
            py = rest[y]
            g = 0.0
            for k in range(inside):
                g += factor[px, k] * factor[py, k] * signs[k]
            coupling = 0.5 / a[union[px]] if x == y else kernel[union[px], union[py]]
            schur[x, y] = coupling - g
    schur[width, width] = CORNER
    own = np.ones(width + 1)
    if signs.min() > 0.0:
        _cholesky(schur, width + 1)  # S is positive definite with U (its diagonal only grows)
    else:
        saved = schur.copy()
        if not _cholesky(schur, width + 1):
            schur[:, :] = saved
            if not _signed_cholesky(schur, width + 1, own):
                return total, False
    for x in range(width):
        total += own[x] * schur[width, x] ** 2
    return total, True

@numba.njit(cache=True, nogil=True)
def _set_total(kernel: np.ndarray, a: np.ndarray, union: np.ndarray) -> tuple[float, bool]:
    """``1^T M^-1 1`` of one set on its own conducting spots: Cholesky of ``M`` bordered by ones,
    or LU with partial pivoting where ``M`` is not positive definite (then ``False``)."""
    spots = union[a[union] > 0.0]
    c = spots.size
    if c == 0:
        return 0.0, True
    matrix = _bordered(kernel, a, spots)
    bordered = matrix.copy()
    if _cholesky(bordered, c + 1):
        total = 0.0
        for k in range(c):
            total += bordered[c, k] ** 2
        return total, True
    bordered[:, :] = matrix
    signs = np.ones(c + 1)
    if _signed_cholesky(bordered, c + 1, signs):
        total = 0.0
        for k in range(c):
            total += signs[k] * bordered[c, k] ** 2
        return total, False
    return _lu_sum(matrix[:c, :c].copy()), False


#: Size from which a factorization calls LAPACK (``potrf`` through NumPy's Cholesky, on a copy)
#: instead of the compiled loop, which is faster on small matrices and 2-4x slower on large ones.
LAPACK_FROM = 64


@numba.njit(cache=True, nogil=True)
def _bordered(kernel: np.ndarray, radius: np.ndarray, spots: np.ndarray) -> np.ndarray:
    """The point model's matrix of ``spots`` bordered by ones: shape (c + 1, c + 1), ``kernel``
    between spots, ``1 / (2 a)`` on the diagonal (``radius`` a, m), a row of ones below and
    :data:`CORNER` at the corner; the border's column above the corner is left unset (the
    factorizations read the lower triangle, LU the leading c x c block)."""
    c = spots.size
    matrix = np.empty((c + 1, c + 1))
    for p in range(c):
        for q in range(c):
            matrix[p, q] = kernel[spots[p], spots[q]]
        matrix[p, p] = 0.5 / radius[spots[p]]
        matrix[c, p] = 1.0
    matrix[c, c] = CORNER
    return matrix


@numba.njit(cache=True, nogil=True)
def _cholesky(matrix: np.ndarray, size: int) -> bool:
    """Lower Cholesky factor of ``matrix[:size, :size]`` in place from its lower triangle (the
    upper is not read); ``False`` where it is not positive definite."""
    if size < LAPACK_FROM:
        return _cholesky_loop(matrix, size)
    full = np.empty((size, size))
    for i in range(size):
        for j in range(i + 1):
            full[i, j] = full[j, i] = matrix[i, j]
    try:
        lower = np.linalg.cholesky(full)
    except Exception:  # not positive definite
        return False
    for i in range(size):
        for j in range(i + 1):
            matrix[i, j] = lower[i, j]
    return True


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _cholesky_loop(matrix: np.ndarray, size: int) -> bool:
    """:func:`_cholesky` by the compiled loop; its inner products may be reassociated (vectorized):
    the same inputs always give the same factor."""
    for j in range(size):
        pivot = matrix[j, j]
        for k in range(j):
            pivot -= matrix[j, k] * matrix[j, k]
        if not pivot > 0.0:
            return False
        pivot = np.sqrt(pivot)
        matrix[j, j] = pivot
        for i in range(j + 1, size):
            value = matrix[i, j]
            for k in range(j):
                value -= matrix[i, k] * matrix[j, k]
            matrix[i, j] = value / pivot
    return True


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _signed_cholesky(matrix: np.ndarray, size: int, signs: np.ndarray) -> bool:
    """Signed Cholesky factor ``matrix[:size, :size] = L D L^T`` (``D = diag(signs)``, +-1) in place
    from the lower triangle, without pivoting: ``L`` in the lower triangle, ``signs`` filled.

    The symmetric indefinite matrices of close large spots have a few negative pivots. ``False``
    where a pivot falls below :data:`SIGNED_PIVOT_FLOOR` of its diagonal entry (``matrix`` and
    ``signs`` then unspecified). Inner products may be reassociated, as in :func:`_cholesky_loop`.
    """
    row = np.empty(size)
    for j in range(size):
        diagonal = matrix[j, j]
        pivot = diagonal
        for k in range(j):
            row[k] = signs[k] * matrix[j, k]
            pivot -= row[k] * matrix[j, k]
        if not abs(pivot) > SIGNED_PIVOT_FLOOR * abs(diagonal):
            return False
        signs[j] = 1.0 if pivot > 0.0 else -1.0
        scale = np.sqrt(abs(pivot))
        matrix[j, j] = scale
        divisor = signs[j] * scale
        for i in range(j + 1, size):
            value = matrix[i, j]
            for k in range(j):
                value -= matrix[i, k] * row[k]
            matrix[i, j] = value / divisor
    return True


@numba.njit(cache=True, nogil=True)
def _lu_sum(matrix: np.ndarray) -> float:
    """``1^T x`` of ``matrix x = 1`` by Gaussian elimination with partial pivoting (in place)."""
    c = matrix.shape[0]
    rhs = np.ones(c)
    for j in range(c):
        pivot = j + np.argmax(np.abs(matrix[j:, j]))
        if pivot != j:
            for k in range(c):
                matrix[j, k], matrix[pivot, k] = matrix[pivot, k], matrix[j, k]
            rhs[j], rhs[pivot] = rhs[pivot], rhs[j]
        for i in range(j + 1, c):
            factor = matrix[i, j] / matrix[j, j]
            for k in range(j, c):
                matrix[i, k] -= factor * matrix[j, k]
            rhs[i] -= factor * rhs[j]
    x = np.zeros(c)
    for i in range(c - 1, -1, -1):
        value = rhs[i]
        for k in range(i + 1, c):
            value -= matrix[i, k] * x[k]
        x[i] = value / matrix[i, i]
    return x.sum()
