"""The predictors' queries: broadcasting (numbers, arrays or DataArrays), their allowed values,
the fitted ranges or domain (queries outside them NaN and the rest answered, none answered
refused, or all answered with a warning with ``extrapolate``), and the output columns both
predictors (:mod:`g2tom.predict.predictor`, :mod:`g2tom.predict.atlas`) answer with."""

from __future__ import annotations

import warnings
from typing import Any, Callable

import numpy as np
import xarray as xr

from g2tom.config import ConfigError
from g2tom.variables import namespace

__all__ = ["ExtrapolationWarning", "SurrogateErrorWarning", "PartlyAnsweredWarning", "OutsideDomainError", "queries",
           "check_values", "outside_ranges", "settle_domain", "OUTPUT_COLUMNS", "Z95"]

#: z of a two-sided 95 % interval of a normal distribution: the mean's band is R exp(-/+ Z95 e).
Z95 = 1.959963984540054


class ExtrapolationWarning(UserWarning):
    """xi, lambda or F' lies outside the range the surrogate was fitted on."""


class SurrogateErrorWarning(UserWarning):
    """The surrogate's local cross-validated error exceeds the warning threshold."""


class PartlyAnsweredWarning(UserWarning):
    """Some queries lie outside the surrogate's domain: they are NaN, the others answered."""


class OutsideDomainError(ConfigError):
    """No query can be answered: the surface or every query lies outside the surrogate's domain."""


def queries(force: Any, xi: Any, lam: Any) -> tuple[list[np.ndarray], Callable[[np.ndarray], Any]]:
    """Flat float arrays of the broadcast queries, and a function that labels a flat result."""
    given = {"force": force, "xi": xi, "lambda": lam}
    if any(isinstance(v, xr.DataArray) for v in given.values()):
        for name, v in given.items():
            if not isinstance(v, xr.DataArray) and np.ndim(v) != 0:
                raise ConfigError(f"{name} is an array but another query is an xarray.DataArray: give DataArrays or scalars")
        arrays = xr.broadcast(*[v if isinstance(v, xr.DataArray) else xr.DataArray(float(v)) for v in given.values()])
        template = arrays[0]
        flat = [np.asarray(a.transpose(*template.dims).values, dtype=float).ravel() for a in arrays]
        coords = {k: c for k, c in template.coords.items() if set(c.dims) <= set(template.dims)}

        def label(values: np.ndarray) -> xr.DataArray:
            return xr.DataArray(values.reshape(template.shape), dims=template.dims, coords=coords)

        return flat, label
    try:
        arrays = [np.asarray(v, dtype=float) for v in given.values()]
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError:
        shapes = ", ".join(f"{n} {np.shape(v)}" for n, v in given.items())
        raise ConfigError(f"force, xi and lambda must be numbers or arrays that broadcast together; got shapes {shapes}") from None
    except TypeError as exc:
        raise ConfigError(f"force, xi and lambda must be numbers ({exc})") from None
    dims = ("query",) if len(shape) == 1 else tuple(f"query_{k}" for k in range(len(shape)))

    def label_np(values: np.ndarray) -> xr.DataArray:
        return xr.DataArray(values.reshape(shape), dims=dims)

    return [np.broadcast_to(a, shape).ravel() for a in arrays], label_np


def check_values(force: np.ndarray, xi: np.ndarray, lam: np.ndarray) -> None:
    """Refuse (ConfigError, naming the first bad query) a force, xi or lambda outside its allowed range."""
    checks = (
        ("force", force, lambda v: np.isfinite(v) & (v > 0), "must be finite and > 0 (N)"),
        ("xi", xi, lambda v: np.isfinite(v) & (v > 0) & (v < 1), "must be in (0, 1)"),
        ("lambda", lam, lambda v: np.isfinite(v) & (v > 0), "must be finite and > 0"),
    )
    for name, values, ok, allowed in checks:
        bad = np.flatnonzero(~ok(values))
        if bad.size:
            where = f" (query {bad[0] + 1} of {values.size})" if values.size > 1 else ""
            raise ConfigError(f"{name} = {float(values[bad[0]])!r}{where} is out of range: {allowed}")


def outside_ranges(ranges: dict[str, tuple[float, float]], values: dict[str, np.ndarray], span: str,
                   force_scale: float) -> tuple[list[tuple[str, str]], np.ndarray]:
    """Every variable outside its range, and why each query is outside.

    Parameters
    ----------
    ranges
        (low, high) by variable name (``force_normalized`` is F').
    values
        The queries' flat arrays by variable name, each of the queries' length.
    span
        What the ranges are, for the texts ("the fitted range", "the domain").
    force_scale
        N per unit F' of this surface: the range of F' is also given in newtons.

    Returns
    -------
    problems : list of (str, str)
        One per variable outside its range: ``"<name> = <value> lies outside <span> [lo, hi]"``
        and what to do (for F': the forces answered, in N; else "").
    why : numpy.ndarray of str
        Per query: the variables outside their ranges (``"F' = 43.78 above 20.4"``); empty inside.
    """
    size = len(next(iter(values.values())))
    why: list[list[str]] = [[] for _ in range(size)]
    problems = []
    for name, v in values.items():
        lo, hi = ranges[name]
        below, above = v < lo * (1 - 1e-12), v > hi * (1 + 1e-12)
        outside = np.flatnonzero(below | above)
        if not outside.size:
            continue
        label = "F'" if name == "force_normalized" else name
        i = outside[0]
        where = f" (query {i + 1} of {v.size}; {outside.size} outside)" if v.size > 1 else ""
        newtons = (f"answered from {lo * force_scale:.3g} N to {hi * force_scale:.3g} N for this surface"
                   if name == "force_normalized" else "")
        problems.append((f"{label} = {v[i]:.6g}{where} lies outside {span} [{lo:.6g}, {hi:.6g}]", newtons))
        for k in outside:
            side, bound = ("below", lo) if below[k] else ("above", hi)
            newton = f" (F {side} {bound * force_scale:.3g} N)" if name == "force_normalized" else ""
            why[k].append(f"{label} = {v[k]:.4g} {side} {bound:.4g}{newton}")
    return problems, np.array(["; ".join(w) for w in why])


def settle_domain(problems: list[tuple[str, str]], why: np.ndarray, extrapolate: bool, owner: str) -> np.ndarray:
    """Which queries are answered: refuse, answer in part, or (extrapolating) answer all with a warning.

    Parameters
    ----------
    problems
        Every variable outside the domain and what to do about it (the surface's groups first,
        then the queries', as :func:`outside_ranges` writes them); empty: all inside.
    why
        Per query, why it is outside the domain ("": inside).
    extrapolate
        Answer every query, with an :class:`ExtrapolationWarning` per problem.
    owner
        The surrogate, named after the first problem's range (" of the atlas surrogate ...").

    Returns
    -------
    numpy.ndarray of bool
        The queries answered (the others are NaN with ``outside_domain`` saying why).

    Raises
    ------
    OutsideDomainError
        Unless ``extrapolate``, when no query is inside (a surface's group outside the domain
        leaves none), naming every problem.

    Warns
    -----
    ExtrapolationWarning
        With ``extrapolate``, per problem.
    PartlyAnsweredWarning
        When some queries are outside and others answered.
    """
    inside = why == ""
    if not problems:
        return inside
    named = [f"{text}{owner if k == 0 else ''}{': ' + advice if advice else ''}"
             for k, (text, advice) in enumerate(problems)]
    if extrapolate:
        for text in named:
            warnings.warn(f"{text}: the prediction is an extrapolation", ExtrapolationWarning, stacklevel=3)
        return np.ones_like(inside)
    if not inside.any():
        raise OutsideDomainError(f"{'; '.join(named)}: the surrogate is not valid there; pass --extrapolate "
                                 "(extrapolate=True) to predict anyway")
    warnings.warn(f"{inside.sum()} of {inside.size} queries answered; {'; '.join(named)}: the other queries are NaN, "
                  "column outside_domain says why", PartlyAnsweredWarning, stacklevel=3)
    return inside


#: Output variables of the predictors: name -> (units, long_name), as the registry
#: (``variables.toml``, namespace ``predict``) declares them.
OUTPUT_COLUMNS: dict[str, tuple[str, str]] = {name: (v.units, v.long_name) for name, v in namespace("predict").items()}
