"""Truncated-SVD polynomial surrogate of a field on the (lambda, xi) grid (Eq. 26).

A field ``M[i, j] = M(lambda_i, xi_j)`` is decomposed as ``M = U S V^T`` and truncated to
rank ``r``. Mode ``k`` is split symmetrically, ``u_k = sqrt(s_k) U[:, k]`` and
``v_k = sqrt(s_k) V[:, k]`` (sign chosen so that ``v_k`` sums to a non-negative number),
and each mode is fitted by least squares with a polynomial in the transformed coordinates
``w = log(lambda)`` and ``z = -log(1 - xi)``:

    M(lambda, xi) ~ sum_k P_k(w) Q_k(z).

Coefficients are stored in ascending powers (``c_0 + c_1 w + ...``).

Cross-validation leaves out one whole row (one lambda) or one whole column (one xi) at a
time, refits the SVD and the polynomials on the rest and predicts the left-out line; the
score is the RMS relative error of all those predictions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as P
from numpy.typing import ArrayLike

__all__ = [
    "SurrogateModel",
    "to_w",
    "to_z",
    "fit_surrogate",
    "evaluate",
    "loo_error",
    "order_scan",
]


def to_w(lam: ArrayLike) -> np.ndarray:
    """w = log(lambda), lambda > 0 (dimensionless)."""
    return np.log(np.asarray(lam, dtype=float))


def to_z(xi: ArrayLike) -> np.ndarray:
    """z = -log(1 - xi), xi in [0, 1) (dimensionless)."""
    return -np.log1p(-np.asarray(xi, dtype=float))


@dataclass(frozen=True)
class SurrogateModel:
    """A fitted rank-r surrogate.

    Attributes
    ----------
    coef_w
        Shape (rank, order_w + 1): polynomial of each lambda mode in w, ascending powers.
    coef_z
        Shape (rank, order_z + 1): polynomial of each xi mode in z, ascending powers.
    modes_w
        Shape (rank, n_lambda): the SVD modes u_k on the grid.
    modes_z
        Shape (rank, n_xi): the SVD modes v_k on the grid.
    singular_values
        All singular values of the grid matrix, descending.
    """

    coef_w: np.ndarray
    coef_z: np.ndarray
    modes_w: np.ndarray
    modes_z: np.ndarray
    singular_values: np.ndarray

    def __call__(self, lam: ArrayLike, xi: ArrayLike) -> np.ndarray:
        """Surrogate value at (lambda, xi), broadcast against each other."""
        return evaluate(self.coef_w, self.coef_z, lam, xi)


def evaluate(coef_w: np.ndarray, coef_z: np.ndarray, lam: ArrayLike, xi: ArrayLike) -> np.ndarray:
    """``sum_k P_k(log lambda) Q_k(-log(1 - xi))`` for coefficient arrays (rank, order+1).

    Parameters
    ----------
    coef_w, coef_z
        Ascending-power coefficients of the lambda and xi modes, one row per mode.
    lam
        Normalized correlation length lambda > 0.
    xi
        Oxide fraction in [0, 1).

    Returns
    -------
    numpy.ndarray
        Broadcast shape of ``lam`` and ``xi``.
    """
    w, z = np.broadcast_arrays(to_w(lam), to_z(xi))
    total = np.zeros(w.shape)
    for cw, cz in zip(np.asarray(coef_w), np.asarray(coef_z)):
        total = total + P.polyval(w, cw) * P.polyval(z, cz)
    return total


def _modes(matrix: np.ndarray, rank: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Symmetrically scaled, sign-fixed SVD modes (rank, n_rows), (rank, n_cols) and s."""
    U, s, Vt = np.linalg.svd(matrix, full_matrices=False)
    root = np.sqrt(s[:rank])
    u = (U[:, :rank] * root).T
    v = Vt[:rank] * root[:, None]
    flip = np.where(v.sum(axis=1) < 0, -1.0, 1.0)
    return u * flip[:, None], v * flip[:, None], s


def _check(matrix: np.ndarray, lam: np.ndarray, xi: np.ndarray, rank: int) -> None:
    if matrix.ndim != 2 or matrix.shape != (lam.size, xi.size):
        raise ValueError(
            f"matrix shape {matrix.shape} does not match (n_lambda, n_xi) = ({lam.size}, {xi.size})"
        )
    if not np.all(np.isfinite(matrix)):
        raise ValueError("matrix holds non-finite values: every (lambda, xi) needs a fit")
    if np.any(lam <= 0) or np.any((xi < 0) | (xi >= 1)):
        raise ValueError(f"lambda = {lam} must be > 0 and xi = {xi} in [0, 1)")
    if rank < 1:
        raise ValueError(f"rank = {rank} is out of range: must be >= 1")


def fit_surrogate(
    matrix: ArrayLike, lam: ArrayLike, xi: ArrayLike, rank: int, order_w: int, order_z: int
) -> SurrogateModel:
    """Fit the rank-``rank`` SVD surrogate with polynomial modes.

    Parameters
    ----------
    matrix
        Field on the grid, shape (n_lambda, n_xi), finite.
    lam
        Grid of lambda, shape (n_lambda,), > 0.
    xi
        Grid of xi, shape (n_xi,), in [0, 1).
    rank
        SVD rank r >= 1; it must not exceed min(n_lambda, n_xi).
    order_w, order_z
        Polynomial orders in w and z; each must be below the number of grid points along
        its axis (so that the least-squares fit is determined).

    Returns
    -------
    SurrogateModel
    """
    matrix = np.asarray(matrix, dtype=float)
    lam = np.asarray(lam, dtype=float)
    xi = np.asarray(xi, dtype=float)
    _check(matrix, lam, xi, rank)
    if rank > min(matrix.shape):
        raise ValueError(f"rank = {rank} is out of range: must be <= {min(matrix.shape)} for this grid")
    if order_w >= lam.size or order_z >= xi.size:
        raise ValueError(
            f"orders (w {order_w}, z {order_z}) are out of range: must be below the number of "
            f"grid points ({lam.size} lambda, {xi.size} xi)"
        )
    u, v, s = _modes(matrix, rank)
    coef_w, coef_z = _fit_modes(u, v, to_w(lam), to_z(xi), order_w, order_z)
    return SurrogateModel(coef_w, coef_z, u, v, s)


def _fit_modes(
    u: np.ndarray, v: np.ndarray, rows: np.ndarray, cols: np.ndarray, order_r: int, order_c: int
) -> tuple[np.ndarray, np.ndarray]:
    """Polynomial coefficients of the row modes in ``rows`` and the column modes in ``cols``."""
    coef_r = np.stack([P.polyfit(rows, uk, order_r) for uk in u])
    coef_c = np.stack([P.polyfit(cols, vk, order_c) for vk in v])
    return coef_r, coef_c


def _predict_left_out_rows(
    matrix: np.ndarray, rows: np.ndarray, cols: np.ndarray, rank: int, order_r: int, order_c: int
) -> np.ndarray:
    """Each row predicted by a surrogate fitted without it (coordinates already transformed)."""
    out = np.empty_like(matrix)
    for i in range(rows.size):
        keep = np.arange(rows.size) != i
        u, v, _ = _modes(matrix[keep], min(rank, keep.sum(), cols.size))
        coef_r, coef_c = _fit_modes(u, v, rows[keep], cols, order_r, order_c)
        out[i] = sum(P.polyval(rows[i], cr) * P.polyval(cols, cc) for cr, cc in zip(coef_r, coef_c))
    return out


def loo_error(
    matrix: ArrayLike, lam: ArrayLike, xi: ArrayLike, rank: int, order_w: int, order_z: int
) -> float:
    """Leave-one-line-out RMS relative error of the surrogate (dimensionless).

    Every lambda row and every xi column is left out in turn and predicted by a surrogate
    fitted to the rest. Returns NaN when the orders cannot be fitted on one line fewer
    (``order_w >= n_lambda - 1`` or ``order_z >= n_xi - 1``).
    """
    matrix = np.asarray(matrix, dtype=float)
    lam = np.asarray(lam, dtype=float)
    xi = np.asarray(xi, dtype=float)
    _check(matrix, lam, xi, rank)
    if order_w >= lam.size - 1 or order_z >= xi.size - 1:
        return float("nan")
    w, z = to_w(lam), to_z(xi)
    rows = _predict_left_out_rows(matrix, w, z, rank, order_w, order_z)
    cols = _predict_left_out_rows(matrix.T, z, w, rank, order_z, order_w).T
    rel = np.concatenate([(rows / matrix - 1.0).ravel(), (cols / matrix - 1.0).ravel()])
    return float(np.sqrt(np.mean(rel**2)))


def order_scan(
    matrix: ArrayLike, lam: ArrayLike, xi: ArrayLike, rank: int, max_w: int, max_z: int
) -> np.ndarray:
    """:func:`loo_error` for every order pair up to (max_w, max_z).

    Returns
    -------
    numpy.ndarray
        Shape (max_w + 1, max_z + 1); entry [p, q] is the error with orders (w p, z q).
    """
    return np.array(
        [[loo_error(matrix, lam, xi, rank, p, q) for q in range(max_z + 1)] for p in range(max_w + 1)]
    )
