"""The discrete contact model (``contact.model = "discrete"``): each surface's own Poisson asperities,
Hertzian caps coupled through the half-space, solved at the Greenwood–Tripp forces of the approaches
(:mod:`g2tom.models.discrete_pool`); the cube on each surface's own spots
(:mod:`g2tom.models.discrete_cube`); its costs (:mod:`g2tom.models.discrete_cost`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from g2tom.compute import ComputeOptions
from g2tom.config import KERNEL_CACHE_BYTES, ConfigError, Scenario
from g2tom.models import discrete_cost, discrete_pool
from g2tom.models.base import ContactModel, PlanWork, TypicalEnsemble
from g2tom.models.cube_settings import CubeSettings
from g2tom.models.discrete_cube import DiscretePool, clean_pool, discrete_chunk
from g2tom.models.lattice_cube import TERMS
from g2tom.models.shared_clean import once
from g2tom.scene import FieldSource

__all__ = ["Discrete", "MIN_TOUCHING"]

#: The fewest asperities Greenwood–Tripp may expect to touch at the heaviest approach for the discrete
#: model: below, a surface of the pool often has none within reach of the sphere (P = e^-5 for
#: none at all), and its solve would need approaches beyond the asperity disc it was drawn on.
MIN_TOUCHING = 5.0


@dataclass(frozen=True)
class Discrete(ContactModel):
    """Discrete asperities with elastic interaction: a pool of drawn surfaces, each its own clean answer."""

    name: ClassVar[str] = "discrete"
    pooled: ClassVar[bool] = True
    spot_rules: ClassVar[tuple[str, ...]] = ("centre", "disc", "segment")
    computes_steps_alone: ClassVar[bool] = True
    has_clean_share: ClassVar[bool] = True
    caps_yield: ClassVar[bool] = True
    #: With the disc rule and the point model, from a fixed 64-realization cube of the discrete study: per
    #: cell 64 (w / (0.9 x 0.025))^2 from its fast-rule half-widths w, clipped to [400, 30,000]: 146,587
    #: realizations over the 108 cells, 188,200 computed in whole batches, 39,800 fields; the largest
    #: count of a cell 9,569 (2026-11-25 and 2026-11-27, at lambda 23, xi 0.9; 175,096 kept in all).
    typical: ClassVar[TypicalEnsemble] = TypicalEnsemble(146_587 / 108, 188_200 / 108, 39_800 / 12, 9_569)

    # ------------------------------------------------------------------ before work
    def check(self, s: Scenario) -> None:
        """Discrete spots take radius weights, insulating films and no lattice term."""
        for name, value, allowed, why in (
            ("cube.weights", s.cube.weights, "radius", "Greenwood's form on discrete spots weights by radii"),
            ("oxide.film", s.oxide.film, "insulating", "resistive films are not implemented on discrete spots"),
        ):
            if value != allowed:
                raise ConfigError(f"{name} = {value!r} is not allowed with contact.model = {self.name!r}: must be "
                                  f"{allowed!r} ({why})")
        if s.cube.lattice_constant != 0:
            raise ConfigError(f"cube.lattice_constant = {s.cube.lattice_constant!r} is not allowed with contact.model "
                              f"= {self.name!r}: must be 0 (discrete spots have no lattice to complete)")

    def check_reach(self, s: Scenario, expected_touching: float) -> None:
        """Refuse a scene where fewer than :data:`MIN_TOUCHING` asperities are expected to touch at the
        heaviest approach."""
        if not expected_touching >= MIN_TOUCHING:
            rough = s.roughness
            raise ConfigError(
                f"contact.model = {self.name!r} is out of range for this scene: about {expected_touching:.3g} "
                f"asperities are expected to touch at the heaviest approach (roughness.sigma = {rough.sigma!r} m, "
                f"roughness.eta = {rough.eta!r} m^-2, loading.delta_min = {s.loading.delta_min!r} sigma); it needs "
                f"at least {MIN_TOUCHING:g} (fewer leave surfaces with no asperity in reach): use contact.model = "
                f"'greenwood_tripp' (the scenario paper_gt)")

    def plan_work(self, s: Scenario, threads: int, typical: float, computed: float, base: PlanWork) -> PlanWork:
        """The pool's solves and one dense solve set per (xi, field), scaled from the default scene's
        measured times by the discrete cost models' ratio (:mod:`g2tom.models.discrete_cost`); a per-step
        target's realizations at the light steps; the dense matrices per thread."""
        dc, t, ox = discrete_cost, threads, s.oxide
        touching, candidates = dc.expected_counts(s)
        surface_scale = dc.surface_seconds(touching, candidates) / dc.DEFAULT_SURFACE_MODEL_S
        field_scale = dc.field_seconds(touching, candidates) / dc.DEFAULT_FIELD_MODEL_S
        contact_s = base.contact_seconds + dc.DISCRETE_SOLVE_S * dc.DEFAULT_STEPS * surface_scale * s.contact.surfaces / t
        contact_s += dc.grown_pool(s, touching, candidates)[1] / t  # the light steps' added surfaces
        n_xi, n_lam = len(ox.xi), len(ox.lambda_)
        per_realization = n_xi * n_lam * dc.DISCRETE_XI_MAP_S[(ox.spot_rule, s.cube.model)] * field_scale / t
        steps, light_s = dc.step_fields(s, touching, candidates, [[typical] * n_lam] * n_xi)
        # the contact's coupling over the candidates and its Newton copies over the touching caps; the
        # cube's kept kernels (one per surface, bounded), a kernel made in a task and the conjugate
        # gradients' union coupling
        spots = float(touching[-1])
        kept = min(KERNEL_CACHE_BYTES, s.contact.surfaces * 8.0 * spots**2)
        return PlanWork(
            contact_seconds=contact_s,
            contact_bytes=base.contact_bytes + t * 8.0 * (float(candidates[-1]) ** 2 + 3.0 * spots**2),
            realization_seconds=per_realization,
            cube_seconds=per_realization * computed + light_s / t,
            cube_fixed_bytes=base.cube_fixed_bytes + (kept + t * 2.0 * 8.0 * spots**2),
            cube_realizations=min(float(ox.max_realizations), base.cube_realizations * float(steps[0, 0, 0]) / typical),
        )

    def plan_lines(self, s: Scenario) -> list[str]:
        """The pool and the counts its costs follow."""
        touching, candidates = discrete_cost.expected_counts(s)
        return [f"discrete asperities: {s.contact.surfaces} surfaces; Greenwood-Tripp expects "
                f"{touching[-1]:.0f} touching and {candidates[-1]:.0f} candidates at the heaviest step (the default "
                f"scene: {discrete_cost.DEFAULT_HEAVIEST_TOUCHING}); the pool's and the cube's times scale from the "
                f"default's by the discrete cost models (dense solves, ~N^3 at large N)"]

    def atlas_scenario(self, s: Scenario, most_surfaces: int, fewest_surfaces: int, touching: float) -> Scenario:
        """As many touching caps in the pool as ``touching``, between the two bounds."""
        heaviest = float(discrete_cost.expected_touching(s)[-1])
        surfaces = min(most_surfaces, max(fewest_surfaces, math.ceil(touching / max(heaviest, 1.0))))
        return dataclasses.replace(s, contact=dataclasses.replace(s.contact, surfaces=surfaces))

    # ------------------------------------------------------------------ the contact stage
    def contact_pool(self, s: Scenario, forces: np.ndarray, lowest_delta: float,
                     options: ComputeOptions | None) -> tuple[dict, dict, dict]:
        """The pool of surfaces at the load steps' forces (:func:`g2tom.models.discrete_pool.solve_pool`)."""
        pool, radius = discrete_pool.solve_pool(s, forces, lowest_delta, options)
        return discrete_pool.variables(s, pool, radius)

    # ------------------------------------------------------------------ the cube stage
    def cube_spots(self, contact: Any, radius: np.ndarray, weights: np.ndarray,
                   settings: CubeSettings) -> tuple[DiscretePool, DiscretePool, CubeSettings]:
        """contact.nc's pool, for both radii and weights."""
        pool = DiscretePool.of(contact)
        return pool, pool, settings

    def chunk(self, source: FieldSource, index: int, realizations: np.ndarray, xi_index: np.ndarray,
              radius: Any, weights: Any, settings: CubeSettings, limit: int | None = None) -> dict[str, Any]:
        """:func:`g2tom.models.discrete_cube.discrete_chunk` (only the steps below ``limit``)."""
        return discrete_chunk(source, index, realizations, xi_index, radius, settings, limit)

    def terms(self, settings: CubeSettings) -> tuple[str, ...]:
        """A direct solve, no solver terms; with the control variate also the spots' ``clean_share``."""
        return TERMS + ("clean_share",) if settings.control_variate else TERMS

    def clean(self, radius: Any, weights: Any, settings: CubeSettings, n_drawn: int) -> dict[str, np.ndarray]:
        """Over the pool's surfaces (at each step, those solved there): the resistance of the mean
        conductance, the self term of the mean self-conductance, the probability of an open circuit."""
        return self._clean(radius, settings.rho, settings.model)

    @staticmethod
    def _clean(pool: DiscretePool, rho: float, model: str) -> dict[str, np.ndarray]:
        """:meth:`clean` by ``model`` (inside :func:`g2tom.models.shared_clean.shared_cleans`, the pool's
        terms once per distinct input)."""
        terms = once(lambda: clean_pool(pool, rho, model), "clean_pool", pool, rho, model)
        resistance = terms["resistance"]
        if pool.steps is None:
            mean, is_open = np.mean, np.isinf(resistance)
        else:  # NaN where a surface was not solved
            mean, is_open = np.nanmean, np.where(np.isnan(resistance), np.nan, np.isinf(resistance))
        with np.errstate(divide="ignore"):
            total = rho / mean(rho / resistance, axis=0)
            own = rho / mean(rho / terms["resistance_self"], axis=0)
        open_ = mean(is_open, axis=0)
        return {"resistance": total, "self": own, "interaction": total - own, "open": open_, "n_drawn": pool.size}

    def clean_conductance(self, radius: Any, weights: Any, settings: CubeSettings, n_drawn: int,
                          kind: str, lattice_constant: float) -> np.ndarray:
        """No lattice term on discrete spots (NaN)."""
        if lattice_constant > 0:
            return np.full(len(settings.crops), np.nan)
        return 1.0 / self._clean(radius, settings.rho, kind)["resistance"]

    def clean_comment(self, s: Scenario, n_drawn: int) -> str:
        """Over the pool's surfaces."""
        return ("the mean conductance (self-conductance) over the "
                f"{n_drawn} discrete surfaces of contact.nc"
                + (" (at each step those solved there: a grown pool)" if s.contact.pool_half_width > 0 else ""))

    def conducting_rule(self, s: Scenario) -> dict[str, Any]:
        """Each realization's surface and its spot rule."""
        return {"conducting_rule": (
            "realization k meets discrete surface k mod contact.surfaces; a spot conducts with radius a where the "
            "field at its centre is below the threshold (spot_rule centre), or with a sqrt(f), f its clean share of "
            "the contact disc (spot_rule disc), or with a h(f) >= a sqrt(f), the conductance of the circular segment "
            "of share f (spot_rule segment)"), "spot_rule": s.oxide.spot_rule}

    # ------------------------------------------------------------------ the reference
    def words(self, s: Scenario) -> list[str]:
        """The model and its pool."""
        return [f"contact.model {s.contact.model}", f"contact.surfaces {s.contact.surfaces}"]

    def discretization(self, s: Scenario) -> str:
        """The model's name."""
        return self.name
