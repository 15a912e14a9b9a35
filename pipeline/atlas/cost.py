"""What an atlas scene costs, before any work: the model behind ``g2tom plan --atlas``.

On Greenwood–Tripp's grid spots a scene costs what :func:`pipeline.before_work.plan.estimate` says
for its cell grid. On discrete asperities (``contact.model = "discrete"``) the cost grows with the
count of touching asperities, not with a grid: every surface of the pool is a dense Newton solve
over its touching caps at every load step, and every oxide field a dense point-interaction solve
over the conducting spots at every step. Both are modelled per load step from Greenwood–Tripp's
expected count of touching asperities N_s and of candidates C_s
(:func:`pipeline.atlas.loads.expected_counts`, within a few % of the discrete pool's at the heavy
steps):

* contact: ``surfaces x sum_s (CONTACT_STEP_S + CONTACT_SQUARE_S C_s^2 + CONTACT_CUBE_S N_s^3)``,
  C_s the expected candidates (asperities above the undeformed indenter);
* cube: ``fields x sum_s (FIELD_STEP_S + FIELD_SQUARE_S N_s^2 + FIELD_MIXED_S C_s N_s + FIELD_CUBE_S N_s^3)``,
  a field
  being one oxide realization at one lambda, all its xi at once (the point solves of a step share
  one factorization);
* fields: per lambda the realizations of its slowest xi: the measured counts of the adaptive
  paper_discrete-like scene (:data:`REFERENCE_FIELDS`, 5 % target) scaled by
  min(1, (:data:`REFERENCE_TOUCHING` / N_mid)^:data:`FIELDS_EXPONENT`) (more spots average more:
  fewer realizations reach the target; fewer spots were not measured to need more) and by
  (0.05 / target)^2, between ``oxide.min_realizations`` and ``oxide.max_realizations``.

The constants are one thread's CPU seconds measured on this 2-core machine (2026-11-27, small
fixed ensembles of design scenes d02, d12, d22, d24: mu 7.07 at Pi 5, 40, 320, and mu 50 at
Pi 320; see each constant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.config import Scenario

__all__ = ["SceneCost", "scene_cost", "discrete_fields"]

#: Contact pool, one surface: seconds per load step, per candidate squared (the coupling kernel
#: over the candidates) and per touching asperity cubed (the Newton factorizations), each summed
#: over the steps; fitted exactly to d12: 0.085 s per surface of 20 steps (candidates <= 832,
#: N <= 249), d22: 11.4 s (6,657, 1,993), d24 (mu 50, Pi 320): 1.94 s (4,792, 469).
CONTACT_STEP_S = 2.0e-4
CONTACT_SQUARE_S = 2.15e-8
CONTACT_CUBE_S = 2.35e-10
#: Cube, one field (all xi): seconds per step, per N^2, per candidate x N and per N^3 of a step,
#: fitted exactly to the compiled (numba) cube of 01f6c8d after a warm-up call: d02: 2.31 ms per field
#: (N <= 31), d12: 11.1 ms (N <= 249), d24: 54.9 ms (N <= 469), d22: 1.99 s (N <= 1,993); fixed
#: ensembles of 16-64 realizations at lambda 1 and 23. The factorizations' N^3 shows from N ~ 1,000
#: (the batched-NumPy cube before it took 1.35 s per field at d22, 5.2 ms at d02); beyond N ~ 2,000
#: (mu ~ 1 at Pi 320: N ~ 6,000) the model is extrapolated.
FIELD_STEP_S = 1.1e-4
FIELD_SQUARE_S = 1.18e-8
FIELD_MIXED_S = 2.07e-9
FIELD_CUBE_S = 5.4e-11
#: Fields per lambda of the reference scene (the adaptive discrete d12, mu 7.07, Pi 40, target
#: 5 %, min 400 realizations): the realizations of the slowest xi at lambda 1, 3, 7, 11, 17, 23.
REFERENCE_FIELDS = (400, 506, 431, 630, 1225, 2016)
#: Its expected touching asperities at the middle step (Greenwood–Tripp), and how the fields a
#: target needs fall with N_mid: the fast rule's half-widths of a fixed 32-realization ensemble at
#: d22 (N_mid 695) ask for 128 and 351 fields at lambda 1 and 23, against d12's 400 (its first
#: batch) and 2,016 measured: a factor 5.7 at lambda 23 for 8x the touching asperities.
REFERENCE_TOUCHING = 87.0
FIELDS_EXPONENT = 0.8
REFERENCE_TARGET = 0.05
#: Seconds of the fits stage per realization and cell (the bootstrap), and the fixed cost of a
#: scene (resolving its loads and domains, the Greenwood–Tripp solve, writing the file).
FITS_S = 2.0e-6
SCENE_S = 3.0


@dataclass(frozen=True)
class SceneCost:
    """One scene's modelled CPU seconds (one thread) and what drives them.

    Attributes
    ----------
    touching
        (steps,) expected touching asperities per load step (discrete), or None on grid spots.
    surfaces
        Discrete pool size (0 on grid spots).
    fields
        Oxide fields computed (all lambda; each serves every xi).
    contact, cube, other
        Seconds of the contact stage, of the cube and of the rest (oxide, fits, fixed costs).
    """

    touching: np.ndarray | None
    surfaces: int
    fields: float
    contact: float
    cube: float
    other: float

    @property
    def seconds(self) -> float:
        """The scene's total."""
        return self.contact + self.cube + self.other


def discrete_fields(scenario: Scenario, touching: np.ndarray) -> float:
    """Typical oxide fields of an adaptive discrete scene (see the module), or the fixed count."""
    ox = scenario.oxide
    if ox.ensemble != "adaptive":
        return float(ox.n_realizations * len(ox.lambda_))
    mid = max(float(touching[touching.size // 2]), 1.0)
    # fewer touching asperities than the reference do not ask for more: at Pi 5 (N_mid 11) the
    # rule asked for 334 and 743 fields at lambda 1 and 23, below the reference's counts
    scale = min(1.0, (REFERENCE_TOUCHING / mid) ** FIELDS_EXPONENT) * (REFERENCE_TARGET / ox.target_half_width) ** 2
    reference = np.interp(np.log(ox.lambda_), np.log([1.0, 3.0, 7.0, 11.0, 17.0, 23.0]), REFERENCE_FIELDS)
    return float(np.sum(np.clip(reference * scale, ox.min_realizations, ox.max_realizations)))


def scene_cost(scenario: Scenario) -> SceneCost:
    """The modelled CPU seconds of one atlas scene (its scenario as :func:`pipeline.atlas.design.scene_scenario`
    makes it), single-threaded."""
    from pipeline.atlas.loads import expected_counts
    from pipeline.before_work import plan

    if scenario.contact.model != "discrete":
        estimates = {e.stage: e.seconds for e in plan.estimate(scenario, 1)}
        counts = plan.realizations(scenario)
        return SceneCost(None, 0, counts.fields * len(scenario.oxide.lambda_), estimates["contact"],
                         estimates["cube"], estimates["oxide"] + estimates["fits"] + SCENE_S)
    n, c = expected_counts(scenario)
    steps = float(n.size)
    contact = scenario.contact.surfaces * (CONTACT_STEP_S * steps + CONTACT_SQUARE_S * float(np.sum(c**2))
                                           + CONTACT_CUBE_S * float(np.sum(n**3)))
    per_field = (FIELD_STEP_S * steps + FIELD_SQUARE_S * float(np.sum(n**2)) + FIELD_MIXED_S * float(np.sum(c * n))
                 + FIELD_CUBE_S * float(np.sum(n**3)))
    fields = discrete_fields(scenario, n)
    cells = len(scenario.oxide.xi) * len(scenario.oxide.lambda_)
    other = SCENE_S + FITS_S * fields / len(scenario.oxide.lambda_) * cells * scenario.fits.n_bootstrap / 100
    return SceneCost(n, scenario.contact.surfaces, fields, contact, per_field * fields, other)
