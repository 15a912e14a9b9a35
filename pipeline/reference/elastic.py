"""The elastic free-surface operator of a half-space on a grid (non-periodic), behind one function.

Everything in :mod:`g2tom.reference` that needs elasticity calls :func:`free_surface` (the
Boussinesq operator: surface pressure on square pixels -> normal surface displacement of an
unbounded half-space, zero at infinity) or :func:`solve_pressure` (the library's constrained
contact solver on the same operator): ``tamaas``' (the reference, on the CPU) or g2tom's own
operator and Polonsky-Keer solver on NumPy or CuPy (:mod:`g2tom.reference.devices`,
:mod:`g2tom.reference.fft_surface`, :mod:`g2tom.reference.polonsky_keer`), tested against
tamaas'.

The half-space has the contact modulus ``E*`` (``tamaas``' Young modulus ``E*`` with Poisson
ratio 0, so its ``E / (1 - nu^2)`` is ``E*``). Tamaas' trap: the modulus and the Poisson ratio
must be set *before* the non-periodic operator is registered, which copies them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from g2tom.reference import devices
from g2tom.reference.fft_surface import FftSurface, fft_surface
from g2tom.reference.polonsky_keer import solve_at_mean_pressure, solve_capped_at_mean_pressure

__all__ = ["FreeSurface", "free_surface", "solve_pressure", "SolverFailure", "MAX_ITERATIONS"]

#: The contact solver's iteration limit (either device).
MAX_ITERATIONS = 10000

_OPERATOR = "boussinesq_non_periodic"


class SolverFailure(RuntimeError):
    """The contact solver failed (e.g. tamaas' NaN on a contact of a single pixel) or did not converge."""


@dataclass
class FreeSurface:
    """The non-periodic Boussinesq operator of an ``n x n`` grid of square pixels.

    Attributes
    ----------
    n
        Pixels along one side.
    pixel
        Pixel side, m.
    e_star
        Contact modulus E*, Pa.
    model
        The backend's model object (used by :func:`solve_pressure`).
    """

    n: int
    pixel: float
    e_star: float
    model: Any

    def __call__(self, pressure: np.ndarray) -> np.ndarray:
        """Normal displacement (m, positive into the half-space) under ``pressure`` (Pa), (n, n)."""
        out = np.zeros((self.n, self.n))
        self.model.operators[_OPERATOR](np.ascontiguousarray(pressure, dtype=float), out)
        return out


def free_surface(n: int, pixel: float, e_star: float, device: str = "cpu",
                 solver: str = "tamaas") -> FreeSurface | FftSurface:
    """The free-surface operator of an ``n x n`` grid of pitch ``pixel`` (m) with modulus ``e_star`` (Pa):
    tamaas' (``solver`` tamaas, the CPU), or g2tom's on NumPy (``cpu``) or CuPy (``gpu``) (a resolved
    device and solver, :mod:`g2tom.reference.devices`)."""
    if solver == "g2tom" or device == "gpu":
        return fft_surface(n, pixel, e_star, devices.namespace(device))
    import tamaas as tm

    tm.set_log_level(tm.LogLevel.error)
    side = n * pixel
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [side, side], [n, n])
    model.E = float(e_star)  # before registerNonPeriodic, which copies them
    model.nu = 0.0
    tm.ModelFactory.registerNonPeriodic(model, _OPERATOR)
    return FreeSurface(n=n, pixel=pixel, e_star=float(e_star), model=model)


def solve_pressure(operator: FreeSurface | FftSurface, heights: np.ndarray, force: float,
                   tolerance: float, hardness: float | None = None) -> np.ndarray:
    """Contact pressure (Pa, (n, n)) of a rigid surface of ``heights`` (m) pressed by ``force`` (N).

    Frictionless, non-adhesive: ``p >= 0``, and where ``p > 0`` the displacement equals the
    heights plus one rigid approach. Polonsky and Keer's constrained conjugate gradients on the
    free-surface operator, to the relative ``tolerance`` of the solver's error measure (tamaas',
    or :mod:`g2tom.reference.polonsky_keer`'s on an :class:`FftSurface`).

    With ``hardness`` H (Pa) the surface is perfectly plastic: ``0 <= p <= H``, the displacement
    equals the heights plus the approach where ``0 < p < H`` only (the surfaces interpenetrate
    where ``p = H``); g2tom's solver only
    (:func:`~g2tom.reference.polonsky_keer.solve_capped_at_mean_pressure`).

    Raises
    ------
    ValueError
        With ``hardness`` on tamaas' operator, or a force the grid cannot carry below H.
    SolverFailure
        If the solver fails or stops above ``tolerance``.
    """
    mean_pressure = force / (operator.n * operator.pixel) ** 2
    if hardness is not None and not isinstance(operator, FftSurface):
        raise ValueError("the hardness-capped (perfectly plastic) contact solve runs on g2tom's solver "
                         "(solver g2tom), not tamaas'")
    if isinstance(operator, FftSurface):
        h = operator.xp.asarray(heights, dtype=float)
        if hardness is None:
            result = solve_at_mean_pressure(operator, h, mean_pressure, tolerance, MAX_ITERATIONS,
                                            start=operator.last_pressure)
        else:
            result = solve_capped_at_mean_pressure(operator, h, mean_pressure, hardness, tolerance, MAX_ITERATIONS,
                                                   start=operator.last_pressure)
        if not result.error <= tolerance:
            raise SolverFailure(f"contact solver stopped at error {result.error:.3g} > tolerance {tolerance:.3g} "
                                f"after {result.iterations} iterations")
        operator.last_pressure = result.pressure
        return operator.to_host(result.pressure)
    import tamaas as tm

    solver = tm.PolonskyKeerRey(operator.model, np.ascontiguousarray(heights, dtype=float), tolerance)
    solver.setIntegralOperator(_OPERATOR)
    solver.max_iter = MAX_ITERATIONS
    try:
        error = solver.solve(mean_pressure)
    except (tm.FloatingPointError, FloatingPointError) as exc:
        raise SolverFailure(f"contact solver failed at F = {force:.4g} N: {str(exc).splitlines()[0]}") from None
    if not error <= tolerance:
        raise SolverFailure(f"contact solver stopped at error {error:.3g} > tolerance {tolerance:.3g}")
    return np.array(operator.model.traction, dtype=float, copy=True)
