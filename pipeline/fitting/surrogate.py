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

Joint fit (``method = "joint"``, :func:`fit_joint`): the same rank-r form, written as
``T(M)(lambda, xi) = sum_k P_k(w) Q_k(z) = a(w)^T C b(z)`` with ``a(w) = (1, w, ..., w^(p-1))``,
``b(z) = (1, z, ..., z^(q-1))`` and a p x q coefficient matrix ``C`` of rank <= r, where ``T``
is ``log`` or the identity. All of ``C`` is fitted at once against the grid values by weighted
least squares (alternating least squares over the two factors of ``C = X Y^T``, started from the
unweighted optimum), each cell weighted by the inverse square of its uncertainty. A rank-r
p x q matrix has ``r (p + q - r)`` free parameters (:func:`free_parameters`). The factors are
stored in the symmetric SVD form of ``C`` (``coef_w = sqrt(s) U^T``, ``coef_z = sqrt(s) V^T``).

Model spec: the joint surrogate's transform string names T and, optionally, the coordinate map
of lambda: ``"log"`` / ``"identity"`` use the paper's ``w = log(lambda)``; ``"log;w=lambda"``
uses ``w = lambda`` and ``"log;w=sqrt"`` ``w = sqrt(lambda)`` (:data:`W_MAPS`,
:func:`model_spec`, :func:`split_spec`). :func:`evaluate` reads the spec, so a stored
``(coef_w, coef_z, spec)`` triple is the whole model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as P
from numpy.typing import ArrayLike

__all__ = [
    "TRANSFORMS",
    "W_MAPS",
    "W_TEXT",
    "model_spec",
    "split_spec",
    "forward_transform",
    "inverse_transform",
    "closed_formula",
    "JointModel",
    "fit_joint",
    "free_parameters",
    "cross_validate",
    "Candidate",
    "select_model",
    "paper_loo_predictions",
    "SurrogateModel",
    "to_w",
    "to_z",
    "fit_surrogate",
    "evaluate",
    "loo_error",
    "order_scan",
]


#: Coordinate maps w(lambda) of the joint surrogate: the paper's log, lambda itself, its square root.
W_MAPS = ("log", "lambda", "sqrt")


def to_w(lam: ArrayLike, w_map: str = "log") -> np.ndarray:
    """w = log(lambda) (default), lambda or sqrt(lambda), lambda > 0 (dimensionless)."""
    lam = np.asarray(lam, dtype=float)
    if w_map == "log":
        return np.log(lam)
    if w_map == "lambda":
        return lam
    if w_map == "sqrt":
        return np.sqrt(lam)
    raise ValueError(f"w map = {w_map!r} is not allowed: must be one of {W_MAPS}")


def model_spec(transform: str, w_map: str) -> str:
    """The spec string of transform T and lambda map: ``"log"`` for (log, log), ``"log;w=lambda"`` otherwise."""
    return transform if w_map == "log" else f"{transform};w={w_map}"


def split_spec(spec: str) -> tuple[str, str]:
    """(transform, w map) of a spec string written by :func:`model_spec`."""
    transform, sep, rest = spec.partition(";")
    if not sep:
        return transform, "log"
    key, _, w_map = rest.partition("=")
    if key != "w" or w_map not in W_MAPS:
        raise ValueError(f"surrogate spec {spec!r} is malformed: expected 'T' or 'T;w=<one of {W_MAPS}>'")
    return transform, w_map


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


def evaluate(
    coef_w: np.ndarray, coef_z: np.ndarray, lam: ArrayLike, xi: ArrayLike, transform: str = "identity"
) -> np.ndarray:
    """``T^-1(sum_k P_k(log lambda) Q_k(-log(1 - xi)))`` for coefficient arrays (rank, order+1).

    Parameters
    ----------
    coef_w, coef_z
        Ascending-power coefficients of the lambda and xi modes, one row per mode.
    lam
        Normalized correlation length lambda > 0.
    xi
        Oxide fraction in [0, 1).
    transform
        ``"identity"`` (the paper's surrogate) or ``"log"`` (the sum is the log of the field),
        optionally with the lambda map (``"log;w=lambda"``, see :func:`model_spec`).

    Returns
    -------
    numpy.ndarray
        Broadcast shape of ``lam`` and ``xi``.
    """
    transform, w_map = split_spec(transform)
    w, z = np.broadcast_arrays(to_w(lam, w_map), to_z(xi))
    total = np.zeros(w.shape)
    for cw, cz in zip(np.asarray(coef_w), np.asarray(coef_z)):
        total = total + P.polyval(w, cw) * P.polyval(z, cz)
    return inverse_transform(total, transform)


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
    _check(matrix, lam, xi, rank)
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


# --------------------------------------------------------------------------- joint fit
#: Cross-validated RMS relative errors below this are exact to rounding: all equally good.
EXACT = 1e-9
#: Transforms T of the field that the joint surrogate is linear-in-coefficients for.
TRANSFORMS = ("log", "identity")


def _transform_pair(transform: str) -> tuple:
    """(T, T^-1) of a transform name; ValueError for an unknown one."""
    pairs = {"log": (np.log, np.exp), "identity": (np.asarray, np.asarray)}
    if transform not in pairs:
        raise ValueError(f"transform = {transform!r} is not allowed: must be one of {TRANSFORMS}")
    return pairs[transform]


def forward_transform(values: ArrayLike, transform: str) -> np.ndarray:
    """T(values): natural log (values > 0) or the identity."""
    return _transform_pair(transform)[0](np.asarray(values, dtype=float))


def inverse_transform(values: ArrayLike, transform: str) -> np.ndarray:
    """T^-1(values): exp or the identity."""
    return _transform_pair(transform)[1](np.asarray(values, dtype=float))


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
        Spec of T and the lambda map (:func:`model_spec`), e.g. ``"log"`` or ``"log;w=lambda"``.
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
        ``"log"`` or ``"identity"``, optionally with the lambda map (:func:`model_spec`).
    sigma
        Uncertainty of ``T(M)`` per cell (same shape, > 0), or None for equal weights.

    Returns
    -------
    JointModel
    """
    values = np.asarray(values, dtype=float)
    lam = np.asarray(lam, dtype=float)
    xi = np.asarray(xi, dtype=float)
    _check(values, lam, xi, rank)
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
        Specs to try (:func:`model_spec` of a transform in :data:`TRANSFORMS` and a map in
        :data:`W_MAPS`).
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


def _poly_text(coef: np.ndarray, var: str) -> str:
    terms = []
    for power, c in enumerate(coef):
        mono = "" if power == 0 else (f"*{var}" if power == 1 else f"*{var}^{power}")
        terms.append(f"{c:+.17g}{mono}")
    return "(" + " ".join(terms) + ")"


#: The lambda map of each spec as a spreadsheet expression of w.
W_TEXT = {"log": "LN(lambda)", "lambda": "lambda", "sqrt": "SQRT(lambda)"}


def closed_formula(coef_w: np.ndarray, coef_z: np.ndarray, transform: str, name: str) -> str:
    """The surrogate as one spreadsheet-style formula in ``w`` and ``z`` (full precision).

    ``z = -LN(1 - xi)``; ``w = LN(lambda)`` for the paper's map (the formula is written in
    ``w``), otherwise the formula is written in ``lambda`` or ``SQRT(lambda)`` directly; e.g.
    ``alpha = EXP((c0 + c1*w)*(d0 + d1*z) + ...)`` for the log transform.
    """
    transform, w_map = split_spec(transform)
    var = "w" if w_map == "log" else W_TEXT[w_map]
    body = " + ".join(f"{_poly_text(cw, var)}*{_poly_text(cz, 'z')}" for cw, cz in zip(coef_w, coef_z))
    return f"{name} = EXP({body})" if transform == "log" else f"{name} = {body}"
