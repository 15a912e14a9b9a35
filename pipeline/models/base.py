"""What a contact model is to the rest of g2tom: :class:`ContactModel`, the strategy chosen once by
``contact.model`` (:func:`g2tom.models.contact_model`).

A contact model owns what differs between models: its checks before work, its share of the contact
stage (beyond the Greenwood–Tripp solution every model's load steps come from), the spots the cube
meets and the cube's unit of work on them, the clean surface's terms, its cost model for
``g2tom plan`` and the atlas, and its words in the outputs. The stages, the plan and the atlas call
these and never ask which model they hold.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from g2tom.config import Scenario

if TYPE_CHECKING:
    from g2tom.compute import ComputeOptions
    from g2tom.models.cube_settings import CubeSettings
    from g2tom.scene import FieldSource

__all__ = ["ContactModel", "TypicalEnsemble", "PlanWork"]


@dataclass(frozen=True)
class TypicalEnsemble:
    """The adaptive ensemble's counts per (xi, lambda) measured on the default scene with a model, for
    ``g2tom plan``: realizations kept, computed (in whole batches), fields per lambda, and the largest
    count of a cell (the cube's padded realization axis)."""

    realizations: float
    computed: float
    fields: float
    largest: float


@dataclass(frozen=True)
class PlanWork:
    """The cost terms of ``g2tom plan`` a contact model sets (seconds of the run's threads, bytes).

    Attributes
    ----------
    contact_seconds, contact_bytes
        The contact stage's time and work memory.
    realization_seconds
        The cube's time per computed realization (every xi and lambda).
    cube_seconds
        The cube's time.
    cube_fixed_bytes
        The cube's memory besides its results.
    cube_realizations
        The cube's padded realization axis (typical).
    """

    contact_seconds: float
    contact_bytes: float
    realization_seconds: float
    cube_seconds: float
    cube_fixed_bytes: float
    cube_realizations: float


class ContactModel(ABC):
    """A contact model (``contact.model``): one stateless object per run, chosen from the registry
    (:data:`g2tom.models.registry.CONTACT_MODELS`); a new model is one subclass (a frozen dataclass, so that
    equal models compare and hash equal, as dask's task keys need) and one registry line."""

    #: The value of ``contact.model`` that selects it.
    name: ClassVar[str]
    #: Each run solves a pool of drawn surfaces, each its own clean answer (else one deterministic
    #: clean answer per load step).
    pooled: ClassVar[bool]
    #: ``oxide.spot_rule`` values its spots take.
    spot_rules: ClassVar[tuple[str, ...]]
    #: Why those are all the rules its spots take (for the check's message).
    spot_rule_reason: ClassVar[str] = ""
    #: Its cube can compute a field at some load steps alone (a per-step ensemble target).
    computes_steps_alone: ClassVar[bool]
    #: Its cube returns each realization's clean share (the control variate's control).
    has_clean_share: ClassVar[bool]
    #: Its caps can be capped at ``material.hardness`` (else elastic only).
    caps_yield: ClassVar[bool]
    #: The adaptive ensemble's typical counts on the default scene (``g2tom plan``).
    typical: ClassVar[TypicalEnsemble]

    # ------------------------------------------------------------------ before work
    def check(self, s: Scenario) -> None:
        """The settings this model rules out besides its spot rules (raises
        :class:`~g2tom.config.ConfigError`, naming the parameter, its value and what is allowed); none by
        default."""

    def check_reach(self, s: Scenario, expected_touching: float) -> None:
        """Refuse a scene this model cannot solve, given the asperities Greenwood–Tripp expects to touch at
        the heaviest approach (none by default)."""

    def plan_work(self, s: Scenario, threads: int, typical: float, computed: float, base: PlanWork) -> PlanWork:
        """This model's cost terms of ``g2tom plan`` from the cell-lattice model's ``base`` (unchanged by default).

        Parameters
        ----------
        s
            The scenario.
        threads
            Threads the run uses.
        typical, computed
            Typical realizations per (xi, lambda) kept and computed (in whole batches)
            (:func:`g2tom.before_work.plan.realizations`).
        base
            The terms as the lattice of cells costs them.
        """
        return base

    def plan_lines(self, s: Scenario) -> list[str]:
        """Lines of ``g2tom plan`` about this model (none by default)."""
        return []

    def atlas_scenario(self, s: Scenario, most_surfaces: int, fewest_surfaces: int, touching: float) -> Scenario:
        """An atlas scene's scenario as this model takes it (unchanged by default).

        Parameters
        ----------
        s
            The scene's scenario.
        most_surfaces, fewest_surfaces
            Bounds of a pool's size.
        touching
            Touching caps the pool should hold at the heaviest step, over its surfaces.
        """
        return s

    # ------------------------------------------------------------------ the contact stage
    def contact_pool(self, s: Scenario, forces: np.ndarray, lowest_delta: float,
                     options: ComputeOptions | None) -> tuple[dict, dict, dict]:
        """Variables, coordinates and attributes this model adds to contact.nc, solved at the load steps'
        ``forces`` (N); the lowest approach of the Greenwood–Tripp solution, ``lowest_delta`` (m). None by default."""
        return {}, {}, {}

    # ------------------------------------------------------------------ the cube stage
    @abstractmethod
    def cube_spots(self, contact: Any, radius: np.ndarray, weights: np.ndarray,
                   settings: CubeSettings) -> tuple[Any, Any, CubeSettings]:
        """The spots the cube's fields meet and the settings its tasks read, from contact.nc and its
        cell maps of spot radii and weights (delta, y, x)."""

    @abstractmethod
    def chunk(self, source: FieldSource, index: int, realizations: np.ndarray, xi_index: np.ndarray,
              radius: Any, weights: Any, settings: CubeSettings, limit: int | None = None) -> dict[str, Any]:
        """The cube's unit of work: the terms (xi, delta, realization) of the fields of ``realizations`` at
        lambda number ``index``, at the fractions ``xi_index`` (the steps below ``limit`` where the model
        computes some steps alone)."""

    @abstractmethod
    def terms(self, settings: CubeSettings) -> tuple[str, ...]:
        """The per-entry terms :meth:`chunk` returns."""

    @abstractmethod
    def clean(self, radius: Any, weights: Any, settings: CubeSettings, n_drawn: int) -> dict[str, np.ndarray]:
        """The oxide-free surface, every spot conducting, over delta: ``resistance``, ``self``,
        ``interaction``, ``open`` (the probability of an open circuit) and ``n_drawn``."""

    @abstractmethod
    def clean_conductance(self, radius: Any, weights: Any, settings: CubeSettings, n_drawn: int,
                          kind: str, lattice_constant: float) -> np.ndarray:
        """The oxide-free conductance (S, over delta) by the resistance model ``kind`` (``greenwood`` or
        ``point``) with ``lattice_constant``, solved tightly; NaN where it does not apply."""

    def crop_error(self, source: FieldSource, radius: Any, weights: Any, settings: CubeSettings,
                   cropped: np.ndarray) -> float:
        """The largest relative change of R from cropping far, tiny spots (0: never cropped)."""
        return 0.0

    @abstractmethod
    def clean_comment(self, s: Scenario, n_drawn: int) -> str:
        """What the cube's clean terms are, in words (their ``comment``)."""

    def conducting_rule(self, s: Scenario) -> dict[str, Any]:
        """The cube's attributes on which spots conduct: ``conducting_rule`` in words, and the settings it
        names."""
        return {"conducting_rule": "a spot conducts where spot_radius > 0 and psi < threshold (float32)"}

    # ------------------------------------------------------------------ the reference
    @abstractmethod
    def words(self, s: Scenario) -> list[str]:
        """The settings that make the model, in words (``contact.model discrete``, ...)."""

    @abstractmethod
    def discretization(self, s: Scenario) -> str:
        """The name of its spots in the full-field validation (``discretization``)."""
