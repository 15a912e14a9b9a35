"""The scenario: every section in one frozen record, its derived values and its provenance.

:class:`Scenario` holds one instance of every section (:data:`SECTIONS`); its config hashes cover
each stage's parameters (:data:`STAGE_INPUTS`) and those of the stages it reads
(:data:`STAGE_UPSTREAM`), so a stage file records exactly what it was built from.
:class:`ResolvedScenario` is a scenario whose ``contact.r_max`` and ``contact.window`` are
resolved numbers (:func:`g2tom.before_work.domains.resolve` makes it): what the stages take,
and the only kind with a cell count (:attr:`ResolvedScenario.n_cells`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass, field
from typing import Any, Self

from g2tom.config.declare import parameter_key
from g2tom.config.scene_sections import Contact, Indenter, Loading, Material, Roughness
from g2tom.config.study_sections import Atlas, Compute, Cube, Fits, Oxide, Surrogate

__all__ = ["SECTIONS", "COMPUTE_SECTION", "STAGE_INPUTS", "STAGE_EXCLUDED", "STAGE_UPSTREAM", "Scenario",
           "ResolvedScenario", "odd_cells"]


SECTIONS: dict[str, type] = {
    "material": Material,
    "roughness": Roughness,
    "indenter": Indenter,
    "loading": Loading,
    "contact": Contact,
    "oxide": Oxide,
    "cube": Cube,
    "fits": Fits,
    "surrogate": Surrogate,
    "atlas": Atlas,
    "compute": Compute,
}
#: The section of compute options (:class:`~g2tom.config.study_sections.Compute`): in no hash.
COMPUTE_SECTION = "compute"

#: Parameters each stage depends on (whole sections or single ``section.key`` entries);
#: a stage's config hash covers these and the hashes of the stages it reads.
STAGE_INPUTS: dict[str, tuple[str, ...]] = {
    # oxide.seed: the discrete pool's surfaces are drawn from it
    "contact": ("material", "roughness", "indenter", "loading", "contact", "oxide.seed"),
    "oxide": ("roughness.eta", "indenter.radius", "contact.window", "oxide"),
    # the fitted steps and fits.confidence: the adaptive ensemble's stopping rule
    "cube": ("material.rho", "cube", "oxide.film", "oxide.film_resistance", "oxide.spot_rule", "fits.min_force",
             "fits.fit_range",
             "fits.min_force_normalized", "fits.confidence", "fits.control_variate"),
    "fits": ("fits",),
    "surrogate": (
        "surrogate.method",
        "surrogate.rank",
        "surrogate.alpha_order_w",
        "surrogate.alpha_order_z",
        "surrogate.gamma_order_w",
        "surrogate.gamma_order_z",
        "surrogate.alpha_transform",
        "surrogate.gamma_transform",
        "surrogate.lambda_map",
        "surrogate.max_rank",
        "surrogate.max_order_w",
        "surrogate.max_order_z",
        "surrogate.weight_floor",
        "surrogate.cv_tolerance",
    ),
}
#: Parameters left out of a stage's inputs although STAGE_INPUTS names their section.
STAGE_EXCLUDED: dict[str, tuple[str, ...]] = {
    "oxide": ("oxide.film", "oxide.film_resistance", "oxide.spot_rule"),
}
#: Parameters left out of every hash while they hold these values (their defaults): a parameter added
#: later keeps the hashes, and so the outputs on disk, of every scenario that does not use it.
HASH_NEUTRAL: dict[str, Any] = {"material.modulus": None, "material.hardness": None, "material.bodies": [],
                                 "fits.control_variate": "none", "contact.pool_half_width": 0.0,
                                 "atlas.heldout_pool_half_width": 0.0, "oxide.step_half_width": 0.0,
                                 "atlas.heldout_step_half_width": 0.0}
#: The stages whose outputs each stage reads (their hashes enter its own).
STAGE_UPSTREAM: dict[str, tuple[str, ...]] = {
    "contact": (),
    "oxide": (),
    "cube": ("contact", "oxide"),
    "fits": ("cube",),
    "surrogate": ("fits",),
}


@dataclass(frozen=True)
class Scenario:
    """A complete, validated parameter set."""

    name: str = "custom"
    description: str = ""
    material: Material = field(default_factory=Material)
    roughness: Roughness = field(default_factory=Roughness)
    indenter: Indenter = field(default_factory=Indenter)
    loading: Loading = field(default_factory=Loading)
    contact: Contact = field(default_factory=Contact)
    oxide: Oxide = field(default_factory=Oxide)
    cube: Cube = field(default_factory=Cube)
    fits: Fits = field(default_factory=Fits)
    surrogate: Surrogate = field(default_factory=Surrogate)
    atlas: Atlas = field(default_factory=Atlas)
    compute: Compute = field(default_factory=Compute)

    # ----------------------------------------------------------------- derived values
    @property
    def deltas(self) -> "list[float]":
        """Approaches delta in m, lightest first."""
        n = self.loading.n_delta
        lo, hi = self.loading.delta_min, self.loading.delta_max
        if n == 1:
            return [hi * self.roughness.sigma]
        return [(hi + (lo - hi) * i / (n - 1)) * self.roughness.sigma for i in range(n)]

    @property
    def cell_size(self) -> float:
        """Cell pitch 1/sqrt(eta), in m."""
        return 1.0 / math.sqrt(self.roughness.eta)

    @property
    def resistance_scale(self) -> float:
        """2 rho* / sqrt(R* sigma), in ohm: R' = R / resistance_scale (Eq. 25)."""
        return 2.0 * self.material.rho / math.sqrt(self.indenter.radius * self.roughness.sigma)

    @property
    def force_scale(self) -> float:
        """E* sqrt(R* sigma^3) / 2, in N: F' = F / force_scale (Eq. 25)."""
        return self.material.E_star * math.sqrt(self.indenter.radius * self.roughness.sigma**3) / 2.0

    @classmethod
    def of(cls, scenario: Scenario, **changes: Any) -> Self:
        """``scenario``'s fields as a ``cls``, those named in ``changes`` replaced.

        ``dataclasses.replace`` keeps the class; this sets it: ``Scenario.of(resolved,
        contact=...)`` is a plain scenario again (its domains to be resolved anew), and
        :func:`g2tom.before_work.domains.resolve` alone makes a :class:`ResolvedScenario`.
        """
        return cls(**{f.name: getattr(scenario, f.name) for f in dataclasses.fields(Scenario)} | changes)

    # ----------------------------------------------------------------- provenance
    def to_dict(self) -> dict[str, Any]:
        """Nested plain dict ``{section: {key: value}}`` plus name and description."""
        out: dict[str, Any] = {"name": self.name, "description": self.description}
        for section in SECTIONS:
            obj = getattr(self, section)
            out[section] = {parameter_key(f): getattr(obj, f.name) for f in dataclasses.fields(obj)}
        return out

    def flat(self) -> dict[str, Any]:
        """``{"section.key": value}`` for every parameter."""
        d = self.to_dict()
        return {f"{s}.{k}": v for s in SECTIONS for k, v in d[s].items()}

    def stage_parameters(self, stage: str) -> dict[str, Any]:
        """The parameters ``stage`` depends on directly, as ``{"section.key": value}``."""
        flat = self.flat()
        wanted = STAGE_INPUTS[stage]
        excluded = STAGE_EXCLUDED.get(stage, ())
        return {
            k: v
            for k, v in flat.items()
            if any(k == w or k.startswith(w + ".") for w in wanted) and k not in excluded
            and not (k in HASH_NEUTRAL and v == HASH_NEUTRAL[k])
        }

    def config_hash(self, stage: str | None = None) -> str:
        """SHA-256 (16 hex digits) of a stage's parameters and its upstream stages' hashes.

        With ``stage=None`` the hash covers the whole scenario (name, description and the compute
        options aside).
        """
        if stage is None:
            payload: Any = {k: v for k, v in self.flat().items() if not (k in HASH_NEUTRAL and v == HASH_NEUTRAL[k])
                            and not k.startswith(COMPUTE_SECTION + ".")}
        else:
            payload = {
                "stage": stage,
                "parameters": self.stage_parameters(stage),
                "upstream": {u: self.config_hash(u) for u in STAGE_UPSTREAM[stage]},
            }
        text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class ResolvedScenario(Scenario):
    """A scenario whose ``contact.r_max`` and ``contact.window`` are resolved numbers, checked
    against the contact they must hold (:func:`g2tom.before_work.domains.resolve` makes it).

    It has no field of its own: the type says that its domains, and so its cell grid, are
    settled. ``dataclasses.replace`` keeps the type, so a resolved scenario with a new window or
    radial domain is made a plain one (:meth:`Scenario.of`) and resolved again.
    """

    @property
    def n_cells(self) -> int:
        """Cells along one side of the window: the odd number closest to window/cell size."""
        return odd_cells(self.contact.window * self.indenter.radius, self.cell_size)


def odd_cells(side: float, cell_size: float) -> int:
    """The odd number of cells of pitch ``cell_size`` closest to ``side / cell_size`` (at least 1).

    Parameters
    ----------
    side
        Length to cover, m (the window's side: ``contact.window`` times R*).
    cell_size
        Cell pitch, m.
    """
    return 2 * max(int(round((side / cell_size - 1.0) / 2.0)), 0) + 1
