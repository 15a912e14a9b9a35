"""Part 2's statistics: ensemble geometric means, their standard errors, and how many realizations a load needs.

Pure numpy. Every mean here is a mean of ``ln R`` over the conducting realizations (``R`` finite
and positive; an open circuit, ``R = +inf``, is counted in the open fraction, not averaged), so
the geometric mean of ``R`` is its exponential and the standard error of ``ln`` of that geometric
mean is the standard error of the mean.

The full field's ensemble at a load is estimated by **two-phase (double) sampling**: a proxy
``d`` (the full field on a coarser grid, or on the GW surface the discrete solve of each surface's
own caps) on ``N`` realizations, and the full field itself ``f`` on the first ``P`` of them (part 1's
realizations, on the main grid). The estimate of ``E[ln R]`` is

    m = mean_N(d) + mean_P(f - d),

unbiased whatever the proxy's own bias (the paired mean difference removes it), with variance

    Var m = var(d) / N + var(e) / P + 2 cov(d, e) / N,    e = f - d,

(the ``P`` pairs are part of the ``N``: ``cov(mean_N d, mean_P e) = cov(d, e) / N``), estimated with
the sample (co)variances (``ddof = 1``). With ``N = P`` it is the plain mean of ``f`` and its
standard error ``sd(f) / sqrt(P)``. Two independent ensembles' standard errors add in squares.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LogMean", "log_mean", "two_phase_log_mean", "ratio_error", "allocation", "cheapest", "prior_log_sd",
           "prior_pairs_sd", "target", "PRIOR_CLEAN_SD", "PRIOR_OXIDE_SD", "PRIOR_PAIRS_CLEAN_SD",
           "PRIOR_PAIRS_OXIDE_SD", "CLEAN_TARGETS", "OXIDE_TARGETS"]

#: Surface-to-surface scatter of the full field's clean ``ln R`` before any is measured: (F', sd)
#: measured outside the project on 16 GW-cap surfaces: 0.32 at F' 0.075, 0.15 at 0.5,
#: 0.08 at 2, ~0.03 from 5. Interpolated in (ln F', ln sd), constant outside.
PRIOR_CLEAN_SD = ((0.075, 0.32), (0.5, 0.15), (2.0, 0.08), (5.0, 0.03))
#: The oxidized scatter before any is measured: (F', sd of ln R per realization, the proxy's share
#: A of :func:`allocation`, the largest of the four oxide cases), the larger of the two default
#: sets' (GW and random process, 8 + 32 or 26 pairs and 40-512 proxies a load, 2026-11-27): oxide
#: switching whole spots on and off scatters more than the surfaces do, ~0.6 up to F' 0.5 where the
#: clean is 0.15-0.3. Interpolated in (ln F', ln sd), constant outside.
PRIOR_OXIDE_SD = ((0.075, 0.75), (0.5, 0.6), (1.5, 0.42), (3.5, 0.30), (6.0, 0.14), (18.8, 0.083))
#: The pairs' scatter before any is measured: (F', sd of ln(full field / proxy) per realization, the
#: pairs' share B of :func:`allocation`), clean and the largest oxidized, measured with
#: :data:`PRIOR_OXIDE_SD` (the 256^2 proxy against the 1024^2 full field: spots a few pixels wide,
#: cut by oxide, at light loads).
PRIOR_PAIRS_CLEAN_SD = ((0.075, 0.042), (0.5, 0.01))
PRIOR_PAIRS_OXIDE_SD = ((0.075, 0.17), (0.45, 0.12), (1.5, 0.032), (3.5, 0.025), (6.0, 0.01))
#: The accuracy targets of the default's ensemble against the full field, |ratio - 1| at F': clean
#: 15 % at F' 0.075, 8 % at 0.5, 5 % from F' 1; oxidized 10 % at F' 1-2 and 7 % from F' 5 (none
#: below F' 1). Between two stated points the target is interpolated in ln F'; outside, the
#: nearest stated one holds.
CLEAN_TARGETS = ((0.075, 0.15), (0.5, 0.08), (1.0, 0.05))
OXIDE_TARGETS = ((1.0, 0.10), (2.0, 0.10), (5.0, 0.07))


@dataclass(frozen=True)
class LogMean:
    """A mean of ``ln R`` over an ensemble.

    Attributes
    ----------
    mean
        Mean of ``ln R`` over the conducting realizations (``ln`` of the geometric mean, R in ohm);
        NaN when none conducts.
    error
        Its standard error (NaN where it cannot be estimated: fewer than two values, or fewer than
        two pairs for a two-phase estimate).
    count
        Realizations in the ensemble (conducting or not).
    open_fraction
        Fraction of them that are open circuits (R = +inf).
    pairs_error
        A two-phase estimate's share of ``error`` from its pairs alone, ``sd(e) / sqrt(P)`` (more
        proxies cannot bring ``error`` below it); NaN for a plain mean.
    """

    mean: float
    error: float
    count: int
    open_fraction: float
    pairs_error: float = math.nan


def _logs(values: np.ndarray) -> np.ndarray:
    """``ln`` of the finite positive entries of ``values`` (1-D), the others dropped."""
    v = np.asarray(values, float).ravel()
    return np.log(v[np.isfinite(v) & (v > 0)])


def _count(values: np.ndarray) -> int:
    """Realizations among ``values`` (NaN entries are not: unsolved)."""
    return int(np.sum(~np.isnan(np.asarray(values, float))))


def _open_fraction(values: np.ndarray) -> float:
    v = np.asarray(values, float).ravel()
    v = v[~np.isnan(v)]
    return float(np.mean(np.isposinf(v))) if v.size else np.nan


def log_mean(values: np.ndarray, deterministic: bool = False) -> LogMean:
    """The plain ensemble mean of ``ln values`` (1-D, ohm; NaN entries are not realizations).

    ``deterministic``: the values are one exact answer, not a sample (g2tom's Greenwood-Tripp
    clean resistance): standard error 0.
    """
    logs = _logs(values)
    count = _count(values)
    mean = float(np.mean(logs)) if logs.size else np.nan
    if deterministic:
        error = 0.0 if logs.size else np.nan
    else:
        error = float(np.std(logs, ddof=1) / math.sqrt(logs.size)) if logs.size >= 2 else np.nan
    return LogMean(mean, error, count, _open_fraction(values))


def _two_phase_terms(proxy: np.ndarray, exact: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The proxy's conducting logs, and over the conducting pairs the proxy's logs and the differences."""
    proxy = np.asarray(proxy, float).ravel()
    exact = np.asarray(exact, float).ravel()
    if exact.size > proxy.size:
        raise ValueError(f"{exact.size} exact values but only {proxy.size} proxies: the exact ones must be a subset")
    head = proxy[:exact.size]
    pair = np.isfinite(head) & (head > 0) & np.isfinite(exact) & (exact > 0)
    d_pair = np.log(head[pair])
    return _logs(proxy), d_pair, np.log(exact[pair]) - d_pair


def two_phase_log_mean(proxy: np.ndarray, exact: np.ndarray) -> LogMean:
    """The two-phase estimate of the full field's mean ``ln R`` (see the module docstring).

    Parameters
    ----------
    proxy
        The proxy's resistances (ohm) on realizations 0 .. N-1 (1-D; +inf: open circuit).
    exact
        The full field's resistances (ohm) on realizations 0 .. P-1, P <= N, paired with
        ``proxy[:P]``.

    Returns
    -------
    LogMean
        Mean of ``ln R``, its standard error and the pairs' share of it; the count and open
        fraction are the proxy's.
    """
    d, d_pair, e = _two_phase_terms(proxy, exact)
    count = _count(proxy)
    if not d.size or not e.size:
        return LogMean(np.nan, np.nan, count, _open_fraction(proxy))
    mean = float(np.mean(d) + np.mean(e))
    if d.size < 2 or e.size < 2:
        return LogMean(mean, np.nan, count, _open_fraction(proxy))
    pairs = np.var(e, ddof=1) / e.size
    var = np.var(d, ddof=1) / d.size + pairs + 2.0 * np.cov(d_pair, e)[0, 1] / d.size
    return LogMean(mean, float(math.sqrt(max(var, 0.0))), count, _open_fraction(proxy), float(math.sqrt(pairs)))


def ratio_error(model: LogMean, reference: LogMean) -> float:
    """Standard error of ``ln(model / reference)`` of two independent ensembles' geometric means."""
    return float(math.hypot(model.error, reference.error))


def allocation(proxy: np.ndarray, exact: np.ndarray, error: float, cap: int, pairs_cap: int, pair_cost: float,
               prior_sd: float | None = None) -> tuple[int, int]:
    """Realizations of the proxy (N) and pairs (P) for the two-phase standard error to reach ``error`` at least cost.

    With the (co)variances of what is there, per realization (open circuits carry no ``ln R``, so a
    term is divided by the share of its values that conduct), the variance is ``A / N + B / P`` with
    ``A = var(d) + 2 cov(d, e)`` (the proxy's share) and ``B = var(e)`` (the pairs'):
    :func:`cheapest` then sizes both. Fewer than two conducting proxies: N from ``prior_sd`` (of
    ``ln R``; the cap without one), P as is; fewer than two conducting pairs: their scatter is
    unknown, taken as 0 (P as is).

    Returns
    -------
    tuple of int
        (N, P): the proxy's realizations, the pairs' (N >= P >= ``exact``'s length).
    """
    exact = np.asarray(exact, float).ravel()
    floor = max(exact.size, 1)
    d, d_pair, e = _two_phase_terms(proxy, exact)
    if d.size < 2:
        n = cap if prior_sd is None else math.ceil((prior_sd / error) ** 2)
        return int(min(cap, max(floor, n))), floor
    spread = np.var(d, ddof=1)
    B = 0.0
    if e.size >= 2:
        spread += 2.0 * np.cov(d_pair, e)[0, 1]
        B = float(np.var(e, ddof=1)) * exact.size / e.size
    A = max(float(spread), 0.0) * _count(proxy) / d.size
    return cheapest(A, B, error, cap, pairs_cap, pair_cost, floor)


def cheapest(A: float, B: float, error: float, cap: int, pairs_cap: int, pair_cost: float,
             floor: int) -> tuple[int, int]:
    """The cheapest (N, P) with ``A / N + B / P <= error^2``: N proxies at cost 1, P pairs at ``pair_cost``.

    Minimizing ``N + pair_cost P`` subject to ``A / N + B / P = error^2`` gives (Lagrange)
    ``N = s sqrt(A) / error^2`` and ``P = s sqrt(B / pair_cost) / error^2`` with
    ``s = sqrt(A) + sqrt(B pair_cost)``: more pairs where the proxy and the full field disagree, more
    proxies where realizations scatter. Then P is held within [``floor``, ``pairs_cap``] and N
    within [P, ``cap``], the other re-solved from the variance where one is held (N at its cap where
    the pairs leave no room; P unchanged where the capped proxies leave none: no pair can help).
    ``A``, ``B``: variances of ``ln R`` per realization (>= 0); ``floor``: the pairs there are.
    """
    pairs_cap = max(pairs_cap, floor)
    V = error**2

    def proxies_for(pairs: float) -> float:  # N that reaches V with P pairs (inf: no N can)
        room = V - B / pairs
        return A / room if room > 0 else math.inf

    def pairs_for(proxies: float) -> float:  # P that reaches V with N proxies
        room = V - A / proxies
        return B / room if room > 0 else math.inf

    s = math.sqrt(A) + math.sqrt(B * pair_cost)
    P = s * math.sqrt(B / pair_cost) / V
    if P < floor or P > pairs_cap:
        P = min(max(P, floor), pairs_cap)
        N = proxies_for(P)
    else:
        N = s * math.sqrt(A) / V
    if N > cap:
        N, need = cap, pairs_for(cap)
        if math.isfinite(need):  # else no count of pairs reaches it beside the capped proxies: P as it was
            P = min(max(need, floor), pairs_cap)
    P = int(min(pairs_cap, max(floor, math.ceil(P - 1e-9))))
    return int(min(cap, max(P, math.ceil(N - 1e-9)))), P


def _interpolated(points: tuple[tuple[float, float], ...], force_normalized: float, log_value: bool) -> float:
    x = np.log([p[0] for p in points])
    y = np.array([p[1] for p in points], float)
    if log_value:
        return float(np.exp(np.interp(math.log(force_normalized), x, np.log(y))))
    return float(np.interp(math.log(force_normalized), x, y))


def prior_log_sd(force_normalized: float, oxidized: bool) -> float:
    """The assumed realization-to-realization sd of ``ln R`` at F' before any is measured
    (:data:`PRIOR_CLEAN_SD`, :data:`PRIOR_OXIDE_SD` oxidized)."""
    return _interpolated(PRIOR_OXIDE_SD if oxidized else PRIOR_CLEAN_SD, force_normalized, log_value=True)


def prior_pairs_sd(force_normalized: float, oxidized: bool) -> float:
    """The assumed sd of ``ln(full field / proxy)`` at F' before any pair is measured
    (:data:`PRIOR_PAIRS_CLEAN_SD`, :data:`PRIOR_PAIRS_OXIDE_SD`)."""
    return _interpolated(PRIOR_PAIRS_OXIDE_SD if oxidized else PRIOR_PAIRS_CLEAN_SD, force_normalized,
                         log_value=True)


def target(force_normalized: float, oxidized: bool) -> float:
    """The accuracy target's allowed |ratio - 1| at F' (:data:`CLEAN_TARGETS`, :data:`OXIDE_TARGETS`); NaN: none."""
    points = OXIDE_TARGETS if oxidized else CLEAN_TARGETS
    if oxidized and force_normalized < points[0][0]:
        return np.nan
    return _interpolated(points, force_normalized, log_value=False)
