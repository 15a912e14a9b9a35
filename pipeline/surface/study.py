"""What ``g2tom surface`` computes: the forces, oxide cases and positions, and the pair's materials."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from g2tom.config import ConfigError, Scenario

__all__ = ["SurfaceStudy", "Spot", "study_of", "stream", "DETRENDS", "EXTENDS", "DEFAULT_POSITIONS"]

#: The most positions taken when none are asked for (the independent windows the map holds, up to it).
DEFAULT_POSITIONS = 16

#: How the map's long-wavelength form is removed before the sphere is added: ``plane`` (the
#: least-squares plane of the measured pixels, a tilted sample) or ``none`` (the heights as given).
DETRENDS = ("plane", "none")
#: What a map smaller than the window becomes: refused (``none``), or windows drawn from the map's own
#: isotropic power spectrum (``spectrum``, :mod:`g2tom.physics.spectrum_synthesis`).
EXTENDS = ("none", "spectrum")


@dataclass(frozen=True)
class Spot:
    """A single contact position chosen by the user: ``x``, ``y`` in m from the map's first pixel's
    centre (x along columns, y along rows), or the map's centre (``centre``)."""

    x: float = math.nan
    y: float = math.nan
    centre: bool = False


@dataclass(frozen=True)
class SurfaceStudy:
    """One ``g2tom surface`` computation.

    Attributes
    ----------
    forces
        Normal forces F, N, ascending.
    xi
        Nominal oxide fractions in (0, 1) (empty: clean only).
    correlation_lengths
        Oxide correlation lengths l_O, m.
    fields
        Oxide fields per position and oxide case.
    positions
        Contact positions spread over the map (ignored with ``at``), or None: every independent
        window the map holds, at most :data:`DEFAULT_POSITIONS` (windows drawn from the spectrum:
        that many).
    at
        A single position chosen by the user, or None.
    window
        Window side in pixels, or None: the smallest that holds the heaviest force's contact.
    detrend
        One of :data:`DETRENDS`.
    extend
        One of :data:`EXTENDS`.
    seed
        Root seed of the positions' order and the oxide fields.
    e_star, rho, hardness
        Contact modulus E* (Pa), resistivity rho* (ohm m), hardness H (Pa; None: elastic).
    shape, radius, cone_angle, punch_radius, edge_radius
        The indenter (:func:`g2tom.physics.indenter.profile`).
    hurst, ks_ratio, amplitudes, resolution, threshold
        The oxide field's spectrum and threshold rule (the scenario's ``oxide.*``).
    tolerance
        The contact solver's relative tolerance.
    """

    forces: tuple[float, ...]
    xi: tuple[float, ...] = ()
    correlation_lengths: tuple[float, ...] = ()
    fields: int = 8
    positions: int | None = None
    at: Spot | None = None
    window: int | None = None
    detrend: str = "plane"
    extend: str = "none"
    seed: int = 20240531
    e_star: float = 1.153846e11
    rho: float = 7.2e-7
    hardness: float | None = None
    shape: str = "sphere"
    radius: float = 10e-3
    cone_angle: float = 0.01
    punch_radius: float = 1e-3
    edge_radius: float = 10e-3
    hurst: float = 0.5
    ks_ratio: float = 3.0
    amplitudes: str = "ideal"
    resolution: float = 8.0
    threshold: str = "theoretical"
    tolerance: float = 1e-8

    @property
    def oxidized(self) -> bool:
        """Whether any oxide case is computed."""
        return bool(self.xi)

    @property
    def indenter(self) -> dict[str, float | str]:
        """The indenter's keyword arguments of :func:`g2tom.physics.indenter.profile`."""
        return {"shape": self.shape, "radius": self.radius, "cone_angle": self.cone_angle,
                "punch_radius": self.punch_radius, "edge_radius": self.edge_radius}

    def parameters(self) -> dict[str, object]:
        """Every setting as netCDF-friendly attributes (None as 'none')."""
        out: dict[str, object] = {}
        for key, value in dataclasses.asdict(self).items():
            if key == "at":
                value = "none" if self.at is None else ("centre" if self.at.centre else f"{self.at.x:g},{self.at.y:g}")
            out[key] = "none" if value is None else (list(value) if isinstance(value, tuple) else value)
        return out


def stream(seed: int, *key: int) -> np.random.Generator:
    """The random stream ``SeedSequence(seed, spawn_key=key)`` (each use of randomness has its own key)."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=tuple(int(k) for k in key))))


def _numbers(name: str, values: object, low: float, high: float, unit: str, open_low: bool = True,
             open_high: bool = True) -> tuple[float, ...]:
    """``values`` as a tuple of floats, each in the range (refused in one line otherwise)."""
    array = np.atleast_1d(np.asarray(values, dtype=float)).ravel()
    inside = ((array > low) if open_low else (array >= low)) & ((array < high) if open_high else (array <= high))
    if array.size == 0 or not np.all(np.isfinite(array) & inside):
        bad = array[~(np.isfinite(array) & inside)] if array.size else array
        shown = f"{bad[0]:g}" if bad.size else "(none)"
        bounds = f"{'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}"
        raise ConfigError(f"{name} = {shown} is out of range: must be in {bounds} ({unit})")
    return tuple(float(v) for v in array)


def study_of(scenario: Scenario, forces: object, *, xi: object = (), correlation_lengths: object = (),
             fields: int = 8, positions: int | None = None, at: Spot | None = None, window: int | None = None,
             detrend: str = "plane", extend: str = "none") -> SurfaceStudy:
    """The study of ``scenario``'s pair of materials, indenter and oxide spectrum at ``forces`` (N).

    Raises
    ------
    ConfigError
        On any setting out of range (one line naming it, its value and the allowed range).
    """
    force = tuple(sorted(_numbers("--force", forces, 0.0, math.inf, "N")))
    xis = _numbers("--xi", xi, 0.0, 1.0, "1") if np.size(xi) else ()
    lengths = _numbers("--correlation-length", correlation_lengths, 0.0, math.inf, "m") \
        if np.size(correlation_lengths) else ()
    if bool(xis) != bool(lengths):
        given, missing = ("--xi", "--correlation-length") if xis else ("--correlation-length", "--xi")
        raise ConfigError(f"{given} is given without {missing}: an oxide case needs both (or neither: clean only)")
    if not 1 <= fields <= 1024:
        raise ConfigError(f"--fields = {fields} is out of range: must be in [1, 1024] (oxide fields per position)")
    if positions is not None and not 1 <= positions <= 4096:
        raise ConfigError(f"--positions = {positions} is out of range: must be in [1, 4096]")
    if window is not None and not 8 <= window <= 8192:
        raise ConfigError(f"--window = {window} is out of range: must be in [8, 8192] (pixels)")
    if detrend not in DETRENDS:
        raise ConfigError(f"--detrend = {detrend!r} is not allowed: must be one of {', '.join(DETRENDS)}")
    if extend not in EXTENDS:
        raise ConfigError(f"--extend = {extend!r} is not allowed: must be one of {', '.join(EXTENDS)}")
    if extend != "none" and at is not None:
        raise ConfigError(f"--extend = {extend!r} is not allowed with --at: a chosen position is a measured window")
    if at is not None and not at.centre and not (math.isfinite(at.x) and math.isfinite(at.y)):
        raise ConfigError(f"--at = {at.x:g},{at.y:g} is out of range: must be finite (m from the centre of the map's "
                          "first pixel), or 'centre'")
    m, ind, ox = scenario.material, scenario.indenter, scenario.oxide
    return SurfaceStudy(
        forces=force, xi=xis, correlation_lengths=lengths, fields=int(fields), positions=None if positions is None else int(positions),
        at=at,
        window=window, detrend=detrend, extend=extend, seed=ox.seed, e_star=m.E_star, rho=m.rho, hardness=m.hardness,
        shape=ind.shape, radius=ind.radius, cone_angle=ind.cone_angle, punch_radius=ind.punch_radius,
        edge_radius=ind.edge_radius, hurst=ox.hurst, ks_ratio=ox.ks_ratio, amplitudes=ox.amplitudes,
        resolution=ox.spectral_resolution, threshold=ox.threshold)
