"""The oxide field's one-point distribution: the probability that a point is clean, exactly.

With "ideal" amplitudes (:mod:`g2tom.physics.oxide_band`) the field at any point is
``psi = sum_k w_k cos(theta_k)``, the phases ``theta_k`` independent and uniform: a stationary
field (a shift only adds to the phases) whose value at a point is not exactly normal. Its
characteristic function is ``phi(u) = prod_k J0(w_k u)``, real and even, so Gil-Pelaez's inversion
gives the distribution function exactly:

    P(psi < t) = 1/2 + (1/pi) int_0^inf sin(t u) phi(u) / u du.

Every point of every realization is clean with this probability, so the spots' clean share
averaged with any fixed weights has it as its expectation: the control variate of the fits stage
(:mod:`g2tom.fitting.control_variate`). On bands of thousands of modes it lies within ~1e-5
of the normal 1 - xi that the theoretical threshold aims at.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate, special

__all__ = ["clean_probability", "MIN_MODES"]

#: Fewest modes accepted: phi(u) must decay (like exp(-u^2 / 2) for many modes of unit total
#: variance) for the integral to converge fast; a field of a few modes is far from that.
MIN_MODES = 16
#: |phi(u)| below which the rest of the integral is dropped.
_TAIL = 1e-13


def clean_probability(weight: np.ndarray, threshold: float) -> float:
    """P(psi < threshold) at one point of the random-phase field of mode amplitudes ``weight``.

    Parameters
    ----------
    weight
        The band's amplitudes ``w_k`` (dimensionless), at least :data:`MIN_MODES`; the field's
        variance is ``sum w_k^2 / 2``.
    threshold
        The threshold ``t`` (the field's units).

    Returns
    -------
    float
        The probability, in [0, 1].

    Raises
    ------
    ValueError
        With fewer than :data:`MIN_MODES` modes.
    """
    weight = np.abs(np.asarray(weight, float).ravel())
    weight = weight[weight > 0]
    if weight.size < MIN_MODES:
        raise ValueError(f"{weight.size} modes: the clean probability needs at least {MIN_MODES}")
    t = float(threshold)

    def log_phi(u: float) -> float:
        return float(np.sum(np.log(np.abs(special.j0(weight * u)) + 1e-300)))

    # the end of the integral: phi below _TAIL (|J0(x)| <= exp(-x^2 / 4) for x <= 2 bounds the
    # start of the decay; step out until the product is negligible)
    scale = 1.0 / np.sqrt(np.sum(weight**2) / 2.0)  # one standard deviation of u's Gaussian
    end = 4.0 * scale
    while log_phi(end) > np.log(_TAIL) and end < 1e4 * scale:
        end *= 1.5

    def integrand(u: float) -> float:
        if u == 0.0:
            return t
        return np.sin(t * u) / u * float(np.prod(special.j0(weight * u)))

    value, _ = integrate.quad(integrand, 0.0, end, limit=500, epsabs=1e-13, epsrel=1e-12)
    return float(min(1.0, max(0.0, 0.5 + value / np.pi)))
