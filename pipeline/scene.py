"""What a scenario's stages, predictor, reference and benchmarks share beyond its contact solution
(:mod:`g2tom.contact_solution`): its dimensionless groups and its oxide fields, regenerable
from their seed. Library code: no I/O, no xarray.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.config import ResolvedScenario, Scenario
from g2tom.physics import oxide_band, oxide_field
from g2tom.physics.groups import Groups, groups

__all__ = ["scene_groups", "bands", "threshold_block", "FieldSource"]


def scene_groups(scenario: Scenario) -> Groups:
    """(mu, Pi) of a scenario's surface and sphere (:mod:`g2tom.physics.groups`)."""
    rough = scenario.roughness
    return groups(rough.sigma, rough.eta, rough.beta, scenario.indenter.radius)


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
