"""What a scenario's stages, predictor, reference and benchmarks share beyond its contact solution
(:mod:`g2tom.contact_solution`): its dimensionless groups and its oxide fields, regenerable
from their seed. Library code: no I/O, no xarray.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.config import ResolvedScenario, Scenario
from g2tom.config.materials import pair_properties
from g2tom.physics import oxide_band, oxide_field, plasticity
from g2tom.physics.groups import Groups, groups

__all__ = ["scene_groups", "Plasticity", "scene_plasticity", "bands", "threshold_block", "FieldSource"]


def scene_groups(scenario: Scenario) -> Groups:
    """(mu, Pi) of a scenario's surface and sphere (:mod:`g2tom.physics.groups`)."""
    rough = scenario.roughness
    return groups(rough.sigma, rough.eta, rough.beta, scenario.indenter.radius)


@dataclass(frozen=True)
class Plasticity:
    """Whether a scene's asperities yield (:mod:`g2tom.physics.plasticity`).

    Attributes
    ----------
    hardness
        The hardness the caps' pressure is capped at, Pa (``material.hardness``); None: elastic caps.
    index
        Plasticity index ``psi``, of ``material.hardness`` or, where that is unset, of the named bodies'
        hardness (``material.bodies``); None where neither is known.
    yield_interference
        A cap's first yield ``omega_c``, m, at the same hardness (None where it is not known).
    known_from
        The parameter the hardness of ``index`` comes from (``""`` where it is not known).
    """

    hardness: float | None
    index: float | None
    yield_interference: float | None
    known_from: str

    @property
    def outside_elastic_range(self) -> bool:
        """Caps held elastic although ``psi`` says they yield (``psi`` > :data:`plasticity.ELASTIC_LIMIT`)."""
        return self.hardness is None and self.index is not None and self.index > plasticity.ELASTIC_LIMIT

    def line(self, sigma: float) -> str:
        """One line for ``g2tom plan``, ``run`` and the report, ``sigma`` the asperity height spread (m)."""
        if self.index is None:
            return ("caps: elastic (Hertz); plasticity index unknown: material.hardness and material.bodies unset")
        known = (f"plasticity index psi = {self.index:.3g} (H from {self.known_from}), first yield at "
                 f"omega_c = {self.yield_interference * 1e9:.3g} nm = {self.yield_interference / sigma:.3g} sigma")
        if self.hardness is None:
            return f"caps: elastic (Hertz; material.hardness unset); {known}"
        return f"caps: capped at H = {self.hardness / 1e9:.3g} GPa (perfectly plastic surface); {known}"

    def warning(self) -> str | None:
        """The one-line warning of a scene whose caps yield but are held elastic, or None."""
        if not self.outside_elastic_range:
            return None
        return (f"plasticity index psi = {self.index:.3g} > {plasticity.ELASTIC_LIMIT:g}: most touching asperities "
                "yield, outside the elastic model's range; set material.hardness to cap their pressure")


def scene_plasticity(scenario: Scenario) -> Plasticity:
    """The scene's :class:`Plasticity` (``psi`` and ``omega_c`` of Greenwood and Williamson's ``beta``)."""
    material, rough = scenario.material, scenario.roughness
    hardness, known_from = material.hardness, "material.hardness"
    if hardness is None and material.bodies:
        hardness, known_from = pair_properties(material.bodies)[2], "material.bodies"
    if hardness is None:
        return Plasticity(None, None, None, "")
    return Plasticity(material.hardness, plasticity.plasticity_index(material.E_star, hardness, rough.sigma, rough.beta),
                      plasticity.yield_interference(rough.beta, material.E_star, hardness), known_from)


def bands(scenario: ResolvedScenario) -> list[oxide_band.Band]:
    """The wave-vector band of every correlation length of the scenario, in ``oxide.lambda`` order.

    ``oxide.period = "window"`` puts the modes on the window's lattice (the published fields);
    ``"spectral"`` on the lattice of :func:`oxide_band.spectral_period` at
    ``oxide.spectral_resolution``.
    """
    ox = scenario.oxide
    out = []
    for lam in ox.lambda_:
        period = None
        if ox.period == "spectral":
            period = oxide_band.spectral_period(scenario.n_cells, lam, ox.spectral_resolution)
        out.append(oxide_band.band(scenario.n_cells, scenario.cell_size, lam, ox.ks_ratio, ox.hurst, period))
    return out


def threshold_block(psi: np.ndarray, *, xi: np.ndarray, rule: str) -> np.ndarray:
    """float32 thresholds (xi, lambda, realization) of a chunk of fields."""
    if rule == "theoretical":
        return _theoretical(xi, psi.shape[:2])
    flat = psi.reshape(psi.shape[:2] + (-1,))
    return np.stack([oxide_field.empirical_threshold(f, xi) for f in flat], axis=1)  # one lambda at a time


def _theoretical(xi: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """float32 theoretical thresholds of ``xi``, shape (xi,) + ``shape``."""
    value = oxide_field.theoretical_threshold(xi).astype(np.float32)
    return np.broadcast_to(value.reshape((-1,) + (1,) * len(shape)), (xi.size,) + shape).copy()


@dataclass(frozen=True)
class FieldSource:
    """Everything needed to regenerate any field and its thresholds from its seed (picklable).

    The oxide stage and the cube's tasks both call it, so a field regenerated in the cube is
    bit-identical to the one recorded in oxide.nc.
    """

    modes: tuple[oxide_band.Band, ...]
    lambdas: tuple[float, ...]
    xi: np.ndarray
    seed: int
    amplitudes: str
    rule: str
    n_cells: int
    cell_size: float

    @classmethod
    def of(cls, scenario: ResolvedScenario) -> "FieldSource":
        """The field source of a resolved scenario (its window sets the cell grid)."""
        ox = scenario.oxide
        return cls(tuple(bands(scenario)), tuple(ox.lambda_), np.asarray(ox.xi, float), ox.seed,
                   ox.amplitudes, ox.threshold, scenario.n_cells, scenario.cell_size)

    def psi(self, index: int, realizations: np.ndarray) -> np.ndarray:
        """Fields of ``realizations`` at lambda number ``index``: float32 (realization, y, x)."""
        return oxide_field.realize(self.modes[index], self.seed, self.lambdas[index], realizations,
                                   self.amplitudes, self.n_cells, self.cell_size)

    def fields(self, index: int, realizations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Fields (realization, y, x) and their float32 thresholds (xi, realization) at lambda ``index``."""
        psi = self.psi(index, realizations)
        return psi, threshold_block(psi[None], xi=self.xi, rule=self.rule)[:, 0]

    def thresholds(self, index: int, realizations: np.ndarray) -> np.ndarray:
        """float32 thresholds (xi, realization) at lambda ``index``: the theoretical rule's without
        synthesizing the fields, the empirical rule's from them."""
        if self.rule == "theoretical":
            return _theoretical(self.xi, (np.size(realizations),))
        return self.fields(index, realizations)[1]
