"""A surrogate of a fitted quantity over (xi, lambda, mu, Pi[, F']): one polynomial in log coordinates.

The coordinates are z = -ln(1 - xi), w = ln(lambda), m = ln(mu), q = ln(Pi) (and L = ln F' for a
quantity that varies with the load, e.g. R' itself), each mapped affinely onto [-1, 1] over the
fitted data (for conditioning); the model is

    T(p) = sum over i + j + k + l (+ n) <= D of c_ijkl(n) z^i w^j m^k q^l (L^n),

T = ln for alpha (positive) and the identity for gamma, fitted by weighted least squares
(weights 1 / sigma^2, sigma one standard deviation of T(p) per point). The total degree D is
chosen by leave-one-group-out cross-validation (a group: one scene, so a degree is judged on
scenes it did not see): the lowest degree whose cross-validated RMS is within
(1 + tolerance) of the best.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

__all__ = ["AtlasModel", "coordinates", "fit_atlas_model", "select_degree", "exponents"]

TRANSFORMS = ("log", "identity")


def coordinates(xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                force_n: np.ndarray | None = None) -> np.ndarray:
    """(n, 4) log coordinates z = -ln(1 - xi), w = ln(lambda), m = ln(mu), q = ln(Pi); (n, 5) with
    L = ln F' when ``force_n`` is given."""
    columns = [-np.log1p(-np.asarray(xi, float)), np.log(lam), np.log(mu), np.log(pi)]
    if force_n is not None:
        columns.append(np.log(force_n))
    return np.column_stack(columns)


def exponents(degree: int, n_vars: int = 4) -> np.ndarray:
    """(terms, n_vars) exponents of every monomial of total degree <= ``degree``, by degree."""
    rows = [e for e in itertools.product(range(degree + 1), repeat=n_vars) if sum(e) <= degree]
    return np.array(sorted(rows, key=lambda e: (sum(e), tuple(-v for v in e))), dtype=int)


@dataclass(frozen=True)
class AtlasModel:
    """A fitted polynomial in the mapped log coordinates.

    Attributes
    ----------
    transform
        ``log`` (the model is ln p) or ``identity``.
    low, high
        (4,) ends of each log coordinate over the fitted data, mapped to -1 and 1.
    powers
        (terms, 4) exponents of the monomials.
    coef
        (terms,) their coefficients.
    """

    transform: str
    low: np.ndarray
    high: np.ndarray
    powers: np.ndarray
    coef: np.ndarray

    def _design(self, x: np.ndarray) -> np.ndarray:
        """(n, terms) monomials of the mapped coordinates: each monomial is a lower one (its
        parent) times one coordinate, so the table costs one product per term and point."""
        u = (2.0 * (x - self.low) / (self.high - self.low) - 1.0).T  # (vars, n)
        rows = np.empty((self.powers.shape[0], u.shape[1]))
        index = {tuple(p): k for k, p in enumerate(self.powers.tolist())}
        for k, p in enumerate(self.powers.tolist()):
            if not any(p):
                rows[k] = 1.0
                continue
            i = next(j for j, e in enumerate(p) if e)
            parent = list(p)
            parent[i] -= 1
            np.multiply(rows[index[tuple(parent)]], u[i], out=rows[k])
        return rows.T

    def transformed(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                    force_n: np.ndarray | None = None) -> np.ndarray:
        """T(p) at the points (arrays of equal size; ``force_n`` for a model over F' too)."""
        return self._design(coordinates(xi, lam, mu, pi, force_n)) @ self.coef

    def __call__(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                 force_n: np.ndarray | None = None) -> np.ndarray:
        """The quantity at the points (arrays of equal size)."""
        t = self.transformed(xi, lam, mu, pi, force_n)
        return np.exp(t) if self.transform == "log" else t


def _transformed(values: np.ndarray, transform: str) -> np.ndarray:
    if transform not in TRANSFORMS:
        raise ValueError(f"transform = {transform!r} is not allowed: must be one of {', '.join(TRANSFORMS)}")
    if transform == "log":
        if np.any(~(values > 0)):
            raise ValueError("transform = 'log' needs positive values")
        return np.log(values)
    return np.asarray(values, float)


def fit_atlas_model(xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray, values: np.ndarray,
                    sigma: np.ndarray, degree: int, transform: str = "log",
                    bounds: tuple[np.ndarray, np.ndarray] | None = None,
                    force_n: np.ndarray | None = None) -> AtlasModel:
    """Weighted least-squares fit of total degree ``degree``.

    Parameters
    ----------
    xi, lam, mu, pi, values
        The fitted points and the parameter there, arrays of size n.
    sigma
        One standard deviation of T(value) per point, > 0.
    degree
        Total degree D >= 0; the fit needs more points than terms.
    transform
        ``log`` or ``identity``.
    bounds
        (low, high) of the log coordinates to map to [-1, 1] (default: the points' own).
    force_n
        F' of each point, for a quantity that varies with the load (a fifth coordinate).

    Raises
    ------
    ValueError
        If there are no more points than terms, or values do not suit the transform.
    """
    x = coordinates(xi, lam, mu, pi, force_n)
    low, high = bounds if bounds is not None else (x.min(axis=0), x.max(axis=0))
    high = np.where(high > low, high, low + 1.0)  # a coordinate held fixed maps to -1
    powers = exponents(degree, x.shape[1])
    if x.shape[0] <= powers.shape[0]:
        raise ValueError(f"{x.shape[0]} points cannot fit degree {degree} ({powers.shape[0]} terms)")
    model = AtlasModel(transform, np.asarray(low, float), np.asarray(high, float), powers, np.zeros(powers.shape[0]))
    weight = 1.0 / np.asarray(sigma, float)
    design = model._design(x) * weight[:, None]
    coef, *_ = np.linalg.lstsq(design, _transformed(values, transform) * weight, rcond=None)
    return AtlasModel(transform, model.low, model.high, powers, coef)


def select_degree(xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray, values: np.ndarray,
                  sigma: np.ndarray, groups: np.ndarray, degrees: range, transform: str = "log",
                  tolerance: float = 0.05, force_n: np.ndarray | None = None) -> tuple[int, dict[int, float]]:
    """The degree chosen by leave-one-group-out cross-validation, and every degree's CV RMS.

    The score is the RMS over all points of T(prediction) - T(value), each point predicted by
    the model fitted without its group; degrees that cannot be fitted without a group score inf.
    """
    x_all = coordinates(xi, lam, mu, pi, force_n)
    bounds = (x_all.min(axis=0), x_all.max(axis=0))
    target = _transformed(values, transform)
    scores: dict[int, float] = {}
    for degree in degrees:
        errors = np.empty(values.size)
        try:
            for g in np.unique(groups):
                out = groups == g
                f_in, f_out = (None, None) if force_n is None else (force_n[~out], force_n[out])
                model = fit_atlas_model(xi[~out], lam[~out], mu[~out], pi[~out], values[~out], sigma[~out],
                                        degree, transform, bounds, f_in)
                errors[out] = model.transformed(xi[out], lam[out], mu[out], pi[out], f_out) - target[out]
        except ValueError:
            scores[degree] = np.inf
            continue
        scores[degree] = float(np.sqrt(np.mean(errors**2)))
    best = min(scores.values())
    if not np.isfinite(best):
        raise ValueError(f"no degree in {list(degrees)} can be cross-validated on {np.unique(groups).size} groups")
    return min(d for d, s in scores.items() if s <= best * (1.0 + tolerance)), scores
