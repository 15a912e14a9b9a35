"""The Greenwood–Tripp contact model (``contact.model = "greenwood_tripp"``): the asperities' mean
(Sect. 2.5) discretized on the cell lattice by ``contact.spots``; the cube on the lattice's spots
(:mod:`g2tom.models.lattice_cube`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from g2tom.config import Scenario
from g2tom.models.base import ContactModel, TypicalEnsemble
from g2tom.models.cube_settings import CubeSettings
from g2tom.models.lattice_cube import asperity_spots, clean_terms, exact_terms, field_chunk, spots_of, terms
from g2tom.models.shared_clean import once
from g2tom.scene import FieldSource

__all__ = ["GreenwoodTripp"]


@dataclass(frozen=True)
class GreenwoodTripp(ContactModel):
    """Greenwood–Tripp's mean contact, its spots on the lattice of cells (one deterministic clean answer)."""

    name: ClassVar[str] = "greenwood_tripp"
    pooled: ClassVar[bool] = False
    spot_rules: ClassVar[tuple[str, ...]] = ("centre",)
    spot_rule_reason: ClassVar[str] = "a grid spot stands for a cell's asperities, not one contact disc"
    computes_steps_alone: ClassVar[bool] = False
    has_clean_share: ClassVar[bool] = False
    caps_yield: ClassVar[bool] = False
    #: Measured (expected spots, fit range F' >= 0.4, 49^2 cells): 361,115 realizations kept over 9 xi x
    #: 12 lambda at target_half_width 0.025 (min 400, cap 30,000, batch 1000); 386,200 computed in whole
    #: batches, 171,200 fields regenerated over the 12 lambdas; the largest cell reached the cap.
    typical: ClassVar[TypicalEnsemble] = TypicalEnsemble(361_115 / 108, 386_200 / 108, 171_200 / 12, 30_000)

    def cube_spots(self, contact: Any, radius: np.ndarray, weights: np.ndarray,
                   settings: CubeSettings) -> tuple[np.ndarray, np.ndarray, CubeSettings]:
        """The cell maps themselves."""
        return radius, weights, settings

    def chunk(self, source: FieldSource, index: int, realizations: np.ndarray, xi_index: np.ndarray,
              radius: Any, weights: Any, settings: CubeSettings, limit: int | None = None) -> dict[str, Any]:
        """:func:`g2tom.models.lattice_cube.field_chunk` (every step)."""
        return field_chunk(source, index, realizations, xi_index, radius, weights, settings)

    def terms(self, settings: CubeSettings) -> tuple[str, ...]:
        """:func:`g2tom.models.lattice_cube.terms`."""
        return terms(settings)

    def clean(self, radius: Any, weights: Any, settings: CubeSettings, n_drawn: int) -> dict[str, np.ndarray]:
        """On the whole window (exact). For ``asperities`` spots, over the first ``n_drawn`` realizations of
        the heights: the resistance of the mean conductance (open circuits conduct nothing), the self term
        of the mean self-conductance, and the probability of an open circuit. Inside
        :func:`g2tom.models.shared_clean.shared_cleans`, once per distinct input."""
        return once(lambda: self._clean(radius, weights, settings, n_drawn),
                    "greenwood_tripp clean", radius, weights, settings, n_drawn)

    @staticmethod
    def _clean(radius: Any, weights: Any, settings: CubeSettings, n_drawn: int) -> dict[str, np.ndarray]:
        """:meth:`clean`, computed."""
        n_delta = radius.shape[0]
        if settings.spots != "asperities":
            res = clean_terms(radius, weights, settings)
            return {"resistance": res.resistance[0], "self": res.resistance_self[0],
                    "interaction": res.resistance_interaction[0], "open": np.zeros(n_delta), "n_drawn": 0}
        drawn = asperity_spots(settings, np.arange(n_drawn))
        res = clean_terms(drawn, drawn, settings)
        rho = settings.rho
        # a step where no drawn spot conducts is an open circuit: R = inf, its interaction part inf - inf = NaN
        with np.errstate(divide="ignore", invalid="ignore"):
            total = rho / np.mean(rho / res.resistance, axis=0)
            own = rho / np.mean(rho / res.resistance_self, axis=0)
            interaction = total - own
        return {"resistance": total, "self": own, "interaction": interaction,
                "open": np.mean(np.isinf(res.resistance), axis=0), "n_drawn": n_drawn}

    def clean_conductance(self, radius: Any, weights: Any, settings: CubeSettings, n_drawn: int,
                          kind: str, lattice_constant: float) -> np.ndarray:
        """NaN where the model does not apply: the point model needs radius weights; the lattice term
        completes expected spots' continuum, and drawn asperities have none to complete."""
        lattice_off = lattice_constant > 0 and settings.spots == "asperities"
        if lattice_off or kind == "point" and weights is not radius and not np.array_equal(weights, radius):
            return np.full(radius.shape[0], np.nan)
        chosen = dataclasses.replace(settings, model=kind, lattice_constant=lattice_constant, film_resistance=np.inf,
                                     solver_tolerance=1e-12, solver_criterion="error", max_iterations=200)
        return 1.0 / self.clean(radius, weights, chosen, n_drawn)["resistance"]

    def crop_error(self, source: FieldSource, radius: Any, weights: Any, settings: CubeSettings,
                   cropped: np.ndarray) -> float:
        """Over the first realization's entries, against the exact whole-window terms."""
        first = np.arange(1)
        exact = exact_terms(source, first, *spots_of(settings, first, radius, weights), settings)["resistance"]
        finite = np.isfinite(exact)
        if not finite.any():
            return 0.0
        return float(np.max(np.abs(cropped[..., :1][finite] / exact[finite] - 1.0)))

    def clean_comment(self, s: Scenario, n_drawn: int) -> str:
        """Drawn asperities' mean, or exact."""
        if s.contact.spots == "asperities":
            return ("the mean conductance (self-conductance) over the first "
                    f"{n_drawn} realizations of the asperity heights")
        return "exact, every spot conducting"

    def words(self, s: Scenario) -> list[str]:
        """The model and its spots."""
        return [f"contact.model {s.contact.model}", f"contact.spots {s.contact.spots}"]

    def discretization(self, s: Scenario) -> str:
        """``contact.spots``."""
        return s.contact.spots
