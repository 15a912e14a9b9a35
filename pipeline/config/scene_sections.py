"""The scene's parameters and its contact: the sections ``material``, ``roughness``, ``indenter``,
``loading`` and ``contact`` (Table 1 of the paper and the Greenwood–Tripp solve's numerics).

Each field declares its unit, meaning and allowed range (:func:`g2tom.config.declare.param`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from g2tom.config.declare import param
from g2tom.config.materials import MATERIALS

__all__ = ["Material", "Roughness", "Indenter", "Loading", "Contact", "MAX_POOL_SURFACES", "POOL_CONFIDENCE"]

#: Most surfaces a grown discrete pool (``contact.pool_half_width`` > 0) solves.
MAX_POOL_SURFACES = 4096
#: Confidence level of ``contact.pool_half_width``.
POOL_CONFIDENCE = 0.95


@dataclass(frozen=True)
class Material:
    """Effective elastic, electrical and plastic properties of the contacting pair (Table 1, and
    named materials: :mod:`g2tom.config.materials`)."""

    E: float = param(2.1e11, "Pa", "Young's modulus of both bodies", gt=0)
    nu: float = param(0.3, "1", "Poisson's ratio of both bodies", gt=-1, lt=0.5)
    rho: float = param(7.2e-7, "ohm m", "effective resistivity rho* = (rho1 + rho2)/2", gt=0)
    modulus: float | None = param(
        None, "Pa", "effective modulus E* of the pair; none: E / (2 (1 - nu^2)) of two bodies of material.E and "
        "material.nu (or the named bodies' pair)", gt=0, unset=True,
    )
    hardness: float | None = param(
        None, "Pa", "indentation hardness H of the softer body: asperity pressure is capped at H (perfectly plastic "
        "surface); none: elastic asperities (the paper's model)", gt=0, le=1e12, unset=True,
    )
    bodies: list[str] = param(
        [], "1", "named materials of the two bodies (one name: both); E*, rho* and H follow from the table where "
        "material.modulus, material.rho and material.hardness are not given: " + ", ".join(MATERIALS),
        choices=tuple(MATERIALS), ordered=False,
    )

    @property
    def E_star(self) -> float:
        """Effective modulus E*, in Pa: ``material.modulus`` where given, else E / (2 (1 - nu^2)) of two
        equal bodies."""
        if self.modulus is not None:
            return self.modulus
        return self.E / (2.0 * (1.0 - self.nu**2))


@dataclass(frozen=True)
class Roughness:
    """Greenwood–Williamson asperity statistics (Table 1)."""

    sigma: float = param(20e-6, "m", "standard deviation of asperity heights", gt=0, le=1)
    eta: float = param(2e8, "m-2", "asperity density (asperities per unit area)", gt=0)
    beta: float = param(30e-6, "m", "mean asperity tip radius", gt=0)


@dataclass(frozen=True)
class Indenter:
    """Axisymmetric indenter profile."""

    shape: str = param(
        "sphere", "1", "indenter profile", choices=("sphere", "cone", "flat_punch")
    )
    radius: float = param(10e-3, "m", "effective radius R* of the sphere", gt=0)
    cone_angle: float = param(
        0.01, "rad", "cone: angle between the flank and the flat (profile r tan angle)", gt=0, lt=math.pi / 2
    )
    punch_radius: float = param(1e-3, "m", "flat punch: radius of the flat face", gt=0)
    edge_radius: float = param(10e-3, "m", "flat punch: radius of the rounded edge", gt=0)


@dataclass(frozen=True)
class Loading:
    """Approaches delta: evenly spaced from ``delta_max`` down to ``delta_min`` (units of sigma)."""

    delta_max: float = param(2.0, "sigma", "first (lightest) approach delta/sigma", ge=-1e3, le=1e3)
    delta_min: float = param(-3.0, "sigma", "last (heaviest) approach delta/sigma", ge=-1e3, le=1e3)
    n_delta: int = param(20, "1", "number of approaches", ge=1, le=1000)


@dataclass(frozen=True)
class Contact:
    """Numerical settings of the Greenwood–Tripp solve and of the discretisation into spots."""

    solver: str = param(
        "newton", "1", "Greenwood–Tripp solver", choices=("newton", "fixed_point")
    )
    n_radial: int = param(720, "1", "number of radial nodes", ge=8)
    r_max: float | str = param(
        "auto", "R*", "outer radius of the radial domain, in units of R*, or auto: until the "
        "pressure is negligible and beyond the spot window's corners", gt=0, auto=True,
    )
    radial_grid: str = param(
        "graded",
        "1",
        "radial nodes: uniform, or uniform where asperities can touch (rigid gap < 4 sigma at "
        "the heaviest approach) and 4 times coarser beyond",
        choices=("uniform", "graded"),
    )
    tolerance: float = param(1e-10, "1", "Newton: relative residual to reach", gt=0, lt=1)
    max_iterations: int = param(200, "1", "iteration limit of either solver", ge=1)
    relaxation: float = param(0.3, "1", "fixed point: relaxation zeta", gt=0, le=1)
    fixed_point_tolerance: float = param(
        1e-3, "1", "fixed point: relative displacement change epsilon", gt=0, lt=1
    )
    area_interpolation: str = param(
        "separation",
        "1",
        "how A* reaches the cell centres: interpolate the separation and evaluate A* there, "
        "or interpolate A* linearly (the published study)",
        choices=("separation", "area_fraction"),
    )
    window: float | str = param(
        "auto", "R*", "side of the square spot window, in units of R*, or auto: every cell whose "
        "spot can change R by more than cube.crop_tolerance at the heaviest load", gt=0, le=1e3, auto=True,
    )
    spots: str = param(
        "expected",
        "1",
        "one spot per cell: expected (radius sqrt(beta) F_1/2(h), the expected sum of asperity "
        "radii; obeys Barber's theorem), mean_area (the paper's radius sqrt(A* dx^2 / pi)) or "
        "asperities (one Gaussian asperity per cell, drawn per realization)",
        choices=("mean_area", "expected", "asperities"),
    )
    model: str = param(
        "greenwood_tripp",
        "1",
        "contact model: greenwood_tripp (the asperities' mean, Sect. 2.5, discretized by contact.spots) "
        "or discrete (each surface's own Poisson asperities, Hertzian caps coupled through the "
        "half-space, solved at the Greenwood-Tripp forces of the approaches)",
        choices=("greenwood_tripp", "discrete"),
    )
    surfaces: int = param(
        256, "1", "discrete: rough surfaces solved at every load step (the pool); oxide realization k meets "
        "surface k mod the pool's size at each step", ge=1,
    )
    pool_half_width: float = param(
        0.0, "1", f"discrete: target relative {POOL_CONFIDENCE:.0%} half-width of the pool's mean clean conductance at "
        "every load step: more surfaces, each solved only up to the last step still short of it (light steps, where "
        f"few asperities touch and surfaces differ most), until met or {MAX_POOL_SURFACES} surfaces; 0: the fixed pool",
        ge=0, lt=1,
    )

