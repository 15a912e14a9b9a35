"""The joint surrogate (``surrogate.method = "joint"``): all coefficients fitted at once, chosen by cross-validation.

The rank-r form of :mod:`g2tom.fitting.surrogate`, written as
``T(M)(lambda, xi) = sum_k P_k(w) Q_k(z) = a(w)^T C b(z)`` with ``a(w) = (1, w, ..., w^(p-1))``,
``b(z) = (1, z, ..., z^(q-1))`` and a p x q coefficient matrix ``C`` of rank <= r, where ``T``
is ``log`` or the identity. All of ``C`` is fitted at once against the grid values by weighted
least squares (alternating least squares over the two factors of ``C = X Y^T``, started from the
unweighted optimum), each cell weighted by the inverse square of its uncertainty
(:func:`fit_joint`). A rank-r p x q matrix has ``r (p + q - r)`` free parameters
(:func:`free_parameters`). The factors are stored in the symmetric SVD form of ``C``
(``coef_w = sqrt(s) U^T``, ``coef_z = sqrt(s) V^T``). Transform, rank and orders are chosen by
leave-one-line-out cross-validation (:func:`select_model`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from g2tom.fitting.surrogate import check_grid, evaluate, forward_transform, split_spec, to_w, to_z

__all__ = ["EXACT", "JointModel", "fit_joint", "free_parameters", "cross_validate", "Candidate", "select_model"]

#: Cross-validated RMS relative errors below this are exact to rounding: all equally good.
EXACT = 1e-9


def free_parameters(rank: int, order_w: int, order_z: int) -> int:
    """Free parameters r (p + q - r) of a rank-r p x q coefficient matrix, r <= min(p, q).

    p = order_w + 1 and q = order_z + 1; a rank above min(p, q) is clipped to it (the full
    tensor-product polynomial, p q parameters).
    """
    p, q = order_w + 1, order_z + 1
    r = min(rank, p, q)
    return r * (p + q - r)


@dataclass(frozen=True)
class JointModel:
    """A jointly fitted rank-r surrogate ``T(M) = sum_k P_k(w) Q_k(z)``.

    Attributes
    ----------
    coef_w
        Shape (rank, order_w + 1): ``P_k`` in ascending powers of w = log(lambda).
    coef_z
        Shape (rank, order_z + 1): ``Q_k`` in ascending powers of z = -log(1 - xi).
    transform
        Spec of T and the lambda map (:func:`g2tom.fitting.surrogate.model_spec`), e.g. ``"log"`` or ``"log;w=lambda"``.
    iterations
        Alternating least-squares sweeps used (0: solved in closed form).
    """

    coef_w: np.ndarray
    coef_z: np.ndarray
    transform: str
    iterations: int

    @property
    def rank(self) -> int:
        """Number of separable terms."""
        return self.coef_w.shape[0]

    def __call__(self, lam: ArrayLike, xi: ArrayLike) -> np.ndarray:
        """Surrogate value at (lambda, xi), broadcast against each other."""
        return evaluate(self.coef_w, self.coef_z, lam, xi, self.transform)


def _vander(x: np.ndarray, order: int) -> np.ndarray:
    return np.vander(x, order + 1, increasing=True)


def _factor(coef: np.ndarray, rank: int) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric, sign-fixed SVD factors (rank, p), (rank, q) of a p x q coefficient matrix."""
    U, s, Vt = np.linalg.svd(coef, full_matrices=False)
    root = np.sqrt(s[:rank])
    fw = (U[:, :rank] * root).T
    fz = Vt[:rank] * root[:, None]
    flip = np.where(fz[:, 0] < 0, -1.0, 1.0)
    return fw * flip[:, None], fz * flip[:, None]


def _kron(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """``np.kron`` of two matrices (rows (i, j), columns (a, b)), without its generic overhead."""
    n, p = left.shape
    m, q = right.shape
    return (left[:, None, :, None] * right[None, :, None, :]).reshape(n * m, p * q)


def _weighted_lstsq(design: np.ndarray, target: np.ndarray, root_w: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(design * root_w[:, None], target * root_w, rcond=None)[0]


def _als(
    t: np.ndarray, weights: np.ndarray, A: np.ndarray, B: np.ndarray, rank: int, tol: float, max_sweeps: int
) -> tuple[np.ndarray, int]:
    """Rank-``rank`` coefficient matrix minimizing sum W (t - A C B^T)^2, and the sweeps used."""
    p, q = A.shape[1], B.shape[1]
    root_w = np.sqrt(weights.ravel())
    target = t.ravel()
    # unweighted optimum: project on the polynomial spaces, truncate the projected matrix
    Qa, Ra = np.linalg.qr(A)
    Qb, Rb = np.linalg.qr(B)
    U, s, Vt = np.linalg.svd(Qa.T @ t @ Qb)
    X = np.linalg.solve(Ra, U[:, :rank] * s[:rank])  # p x r
    Y = np.linalg.solve(Rb, Vt[:rank].T)  # q x r
    if np.allclose(weights, weights.flat[0]):
        return X @ Y.T, 0

    def objective(C: np.ndarray) -> float:
        return float(np.sum(weights * (t - A @ C @ B.T) ** 2))

    previous = objective(X @ Y.T)
    sweep = 0
    for sweep in range(1, max_sweeps + 1):
        X = _weighted_lstsq(_kron(A, B @ Y), target, root_w).reshape(p, rank)
        Y = _weighted_lstsq(_kron(A @ X, B), target, root_w).reshape(rank, q).T
        current = objective(X @ Y.T)
        if previous - current <= tol * max(previous, 1e-300):
            break
        previous = current
    return X @ Y.T, sweep


def fit_joint(
    values: ArrayLike,
    lam: ArrayLike,
    xi: ArrayLike,
    rank: int,
    order_w: int,
    order_z: int,
    transform: str = "log",
    sigma: ArrayLike | None = None,
    tol: float = 1e-12,
    max_sweeps: int = 2000,
) -> JointModel:
    """Fit all coefficients of the rank-``rank`` surrogate jointly by weighted least squares.

    Minimizes ``sum_ij ((T(M_ij) - a(w_i)^T C b(z_j)) / sigma_ij)^2`` over p x q matrices C of
    rank <= ``rank`` (p = order_w + 1, q = order_z + 1). With rank >= min(p, q) the problem is
    linear and solved directly; otherwise by alternating least squares on ``C = X Y^T`` from
    the unweighted optimum (exact for equal weights), until the objective decreases by less
    than ``tol`` relative.

    Parameters
    ----------
    values
        Field on the grid, shape (n_lambda, n_xi), finite (and > 0 for ``transform="log"``).
    lam, xi
        Grid of lambda (> 0) and xi (in [0, 1)).
    rank
        r >= 1.
    order_w, order_z
        Polynomial orders in w and z, each below the number of grid points along its axis.
    transform
        ``"log"`` or ``"identity"``, optionally with the lambda map (:func:`g2tom.fitting.surrogate.model_spec`).
    sigma
        Uncertainty of ``T(M)`` per cell (same shape, > 0), or None for equal weights.

    Returns
    -------
    JointModel
    """
    values = np.asarray(values, dtype=float)
    lam = np.asarray(lam, dtype=float)
    xi = np.asarray(xi, dtype=float)
    check_grid(values, lam, xi, rank)
    if order_w >= lam.size or order_z >= xi.size or order_w < 0 or order_z < 0:
        raise ValueError(
            f"orders (w {order_w}, z {order_z}) are out of range: must be >= 0 and below the number of "
            f"grid points ({lam.size} lambda, {xi.size} xi)"
        )
    field, w_map = split_spec(transform)
    if field == "log" and np.any(values <= 0):
        raise ValueError("transform = 'log' needs a positive field")
    t = forward_transform(values, field)
    with np.errstate(divide="ignore"):
        weights = np.ones_like(t) if sigma is None else 1.0 / np.asarray(sigma, dtype=float) ** 2
    if weights.shape != t.shape or not np.all(np.isfinite(weights) & (weights > 0)):
        raise ValueError("sigma must be finite and > 0 on every cell of the grid")
    A, B = _vander(to_w(lam, w_map), order_w), _vander(to_z(xi), order_z)
    r = min(rank, order_w + 1, order_z + 1)
    if r == min(order_w + 1, order_z + 1):
        coef = _weighted_lstsq(_kron(A, B), t.ravel(), np.sqrt(weights.ravel())).reshape(order_w + 1, order_z + 1)
        sweeps = 0
    else:
        coef, sweeps = _als(t, weights, A, B, r, tol, max_sweeps)
    coef_w, coef_z = _factor(coef, r)
    return JointModel(coef_w, coef_z, transform, sweeps)


def cross_validate(
    values: ArrayLike,
    lam: ArrayLike,
    xi: ArrayLike,
    rank: int,
    order_w: int,
    order_z: int,
    transform: str = "log",
    sigma: ArrayLike | None = None,
) -> np.ndarray | None:
    """Leave-one-line-out predictions of :func:`fit_joint`, shape (2, n_lambda, n_xi).

    ``[0]``: each lambda row predicted by a model fitted to the other rows; ``[1]``: each xi
    column by a model fitted to the other columns. None when one line fewer cannot determine
    the orders (``order_w >= n_lambda - 1`` or ``order_z >= n_xi - 1``).
    """
    values = np.asarray(values, dtype=float)
    lam = np.asarray(lam, dtype=float)
    xi = np.asarray(xi, dtype=float)
    if order_w >= lam.size - 1 or order_z >= xi.size - 1:
        return None
    sigma = np.ones_like(values) if sigma is None else np.asarray(sigma, dtype=float)
    out = np.empty((2,) + values.shape)
    for i in range(lam.size):
        keep = np.arange(lam.size) != i
        model = fit_joint(values[keep], lam[keep], xi, rank, order_w, order_z, transform, sigma[keep])
        out[0, i] = model(lam[i], xi)
    for j in range(xi.size):
        keep = np.arange(xi.size) != j
        model = fit_joint(values[:, keep], lam, xi[keep], rank, order_w, order_z, transform, sigma[:, keep])
        out[1, :, j] = model(lam, xi[j])
    return out


@dataclass(frozen=True)
class Candidate:
    """One model tried by :func:`select_model` and its cross-validated score.

    ``score`` is the leave-one-line-out RMS relative error (NaN: not cross-validatable) and
    ``predictions`` the left-out predictions of :func:`cross_validate` (None likewise).
    """

    transform: str
    rank: int
    order_w: int
    order_z: int
    score: float
    predictions: np.ndarray | None

    @property
    def free_parameters(self) -> int:
        """r (p + q - r)."""
        return free_parameters(self.rank, self.order_w, self.order_z)


def select_model(
    values: ArrayLike,
    lam: ArrayLike,
    xi: ArrayLike,
    transforms: tuple[str, ...],
    max_rank: int,
    max_order_w: int,
    max_order_z: int,
    sigma_of: "dict[str, np.ndarray] | None" = None,
    tolerance: float = 0.1,
) -> tuple[Candidate, list[Candidate]]:
    """Choose transform, rank and orders by leave-one-line-out cross-validation.

    Every transform, every order pair up to the maxima and every rank up to
    ``min(max_rank, p, q)`` is scored by the RMS relative error of its left-out predictions.
    The chosen model is the one with the fewest free parameters whose score is within
    ``(1 + tolerance)`` times the best score, or below :data:`EXACT` (ties: the lower score).

    Parameters
    ----------
    values
        Field on the grid (n_lambda, n_xi).
    lam, xi
        The grid.
    transforms
        Specs to try (:func:`~g2tom.fitting.surrogate.model_spec` of a transform in
        :data:`~g2tom.fitting.surrogate.TRANSFORMS` and a map in
        :data:`~g2tom.fitting.surrogate.W_MAPS`).
    max_rank, max_order_w, max_order_z
        Scan limits.
    sigma_of
        Transform (without the map) -> uncertainty of T(M) per cell (weights 1/sigma^2); None: equal weights.
    tolerance
        Relative slack on the best score that buys a simpler model (dimensionless, >= 0).

    Returns
    -------
    (Candidate, list of Candidate)
        The chosen model and every candidate tried.

    Raises
    ------
    ValueError
        If no candidate can be cross-validated on this grid.
    """
    values = np.asarray(values, dtype=float)
    tried: list[Candidate] = []
    for transform in transforms:
        field = split_spec(transform)[0]
        if field == "log" and np.any(values <= 0):
            continue
        sigma = None if sigma_of is None else sigma_of[field]
        for ow in range(max_order_w + 1):
            for oz in range(max_order_z + 1):
                for rank in range(1, min(max_rank, ow + 1, oz + 1) + 1):
                    pred = cross_validate(values, lam, xi, rank, ow, oz, transform, sigma)
                    score = float("nan") if pred is None else float(np.sqrt(np.mean((pred / values - 1.0) ** 2)))
                    tried.append(Candidate(transform, rank, ow, oz, score, pred))
    scored = [c for c in tried if np.isfinite(c.score)]
    if not scored:
        raise ValueError("no surrogate order can be cross-validated on this grid (need >= 3 points per axis)")
    best = min(c.score for c in scored)
    eligible = [c for c in scored if c.score <= max(best * (1.0 + tolerance), EXACT)]
    return min(eligible, key=lambda c: (c.free_parameters, c.score)), tried
