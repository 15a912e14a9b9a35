"""The surrogate of a field on the (lambda, xi) grid (Eq. 26): its form, coordinates and formula.

A surrogate of rank ``r`` writes a field ``M(lambda, xi)``, or its log, as a sum of separable
terms,

    T(M)(lambda, xi) = sum_k P_k(w) Q_k(z),

with polynomials ``P_k``, ``Q_k`` in the transformed coordinates ``w = log(lambda)`` and
``z = -log(1 - xi)``, coefficients in ascending powers (``c_0 + c_1 w + ...``). Two fits make
one: the paper's SVD-then-polyfit (:mod:`g2tom.fitting.surrogate_paper`) and the joint
weighted fit with cross-validated transform, rank and orders
(:mod:`g2tom.fitting.surrogate_joint`).

Model spec: the joint surrogate's transform string names T and, optionally, the coordinate map
of lambda: ``"log"`` / ``"identity"`` use the paper's ``w = log(lambda)``; ``"log;w=lambda"``
uses ``w = lambda`` and ``"log;w=sqrt"`` ``w = sqrt(lambda)`` (:data:`W_MAPS`,
:func:`model_spec`, :func:`split_spec`). :func:`evaluate` reads the spec, so a stored
``(coef_w, coef_z, spec)`` triple is the whole model; :func:`closed_formula` writes it out.
"""

from __future__ import annotations

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
    "check_grid",
    "to_w",
    "to_z",
    "evaluate",
]


#: Coordinate maps w(lambda) of the joint surrogate: the paper's log, lambda itself, its square root.
W_MAPS = ("log", "lambda", "sqrt")
#: Transforms T of the field that the joint surrogate is linear-in-coefficients for.
TRANSFORMS = ("log", "identity")


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


def check_grid(matrix: np.ndarray, lam: np.ndarray, xi: np.ndarray, rank: int) -> None:
    """ValueError unless ``matrix`` is a finite (n_lambda, n_xi) field on a valid grid and ``rank >= 1``."""
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
