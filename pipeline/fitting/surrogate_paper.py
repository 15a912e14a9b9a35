"""The paper's surrogate (Sect. 3.1): truncated SVD of the grid, each mode fitted by a polynomial.

A field ``M[i, j] = M(lambda_i, xi_j)`` is decomposed as ``M = U S V^T`` and truncated to
rank ``r``. Mode ``k`` is split symmetrically, ``u_k = sqrt(s_k) U[:, k]`` and
``v_k = sqrt(s_k) V[:, k]`` (sign chosen so that ``v_k`` sums to a non-negative number),
and each mode is fitted by least squares with a polynomial in the transformed coordinates
``w = log(lambda)`` and ``z = -log(1 - xi)``:

    M(lambda, xi) ~ sum_k P_k(w) Q_k(z).

Cross-validation leaves out one whole row (one lambda) or one whole column (one xi) at a
time, refits the SVD and the polynomials on the rest and predicts the left-out line; the
score is the RMS relative error of all those predictions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as P
from numpy.typing import ArrayLike

from g2tom.fitting.surrogate import check_grid, evaluate, to_w, to_z

__all__ = ["SurrogateModel", "fit_surrogate", "paper_loo_predictions", "loo_error", "order_scan"]


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


def _modes(matrix: np.ndarray, rank: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Symmetrically scaled, sign-fixed SVD modes (rank, n_rows), (rank, n_cols) and s."""
    U, s, Vt = np.linalg.svd(matrix, full_matrices=False)
    root = np.sqrt(s[:rank])
    u = (U[:, :rank] * root).T
    v = Vt[:rank] * root[:, None]
    flip = np.where(v.sum(axis=1) < 0, -1.0, 1.0)
    return u * flip[:, None], v * flip[:, None], s


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
    check_grid(matrix, lam, xi, rank)
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
    predictions = paper_loo_predictions(matrix, lam, xi, rank, order_w, order_z)
    if predictions is None:
        return float("nan")
    rel = (predictions / matrix - 1.0).ravel()
    return float(np.sqrt(np.mean(rel**2)))


def paper_loo_predictions(
    matrix: ArrayLike, lam: ArrayLike, xi: ArrayLike, rank: int, order_w: int, order_z: int
) -> np.ndarray | None:
    """Left-out-line predictions of the paper's surrogate, shape (2, n_lambda, n_xi).

    ``[0]``: each lambda row predicted by a surrogate fitted without that row; ``[1]``: each
    xi column likewise. None when one line fewer cannot determine the orders.
    """
    matrix = np.asarray(matrix, dtype=float)
    lam = np.asarray(lam, dtype=float)
    xi = np.asarray(xi, dtype=float)
    check_grid(matrix, lam, xi, rank)
    if order_w >= lam.size - 1 or order_z >= xi.size - 1:
        return None
    w, z = to_w(lam), to_z(xi)
    rows = _predict_left_out_rows(matrix, w, z, rank, order_w, order_z)
    cols = _predict_left_out_rows(matrix.T, z, w, rank, order_z, order_w).T
    return np.stack([rows, cols])


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
