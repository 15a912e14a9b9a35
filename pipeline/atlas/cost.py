"""What an atlas scene costs, before any work: the model behind ``g2tom plan --atlas``.

On Greenwood–Tripp's grid spots a scene costs what :func:`g2tom.before_work.plan.estimate` says
for its cell grid. On discrete asperities (a pooled contact model) the pool and every oxide
field cost what :mod:`g2tom.models.discrete_cost` models from Greenwood–Tripp's expected
counts of touching asperities N_s and candidates C_s per load step, and the fields are counted here:

* fields: per lambda the realizations of its slowest xi: the measured counts of the adaptive
  paper_discrete-like scene (:data:`REFERENCE_FIELDS`, 5 % target) scaled by
  min(1, (:data:`REFERENCE_TOUCHING` / N_mid)^:data:`FIELDS_EXPONENT`) (more spots average more:
  fewer realizations reach the target; fewer spots were not measured to need more) and by
  (0.05 / target)^2, between ``oxide.min_realizations`` and ``oxide.max_realizations``;
* the cube: a field computes every xi in the first round, but later rounds only the xi whose
  interval is still open, so each xi costs its own realizations: the slowest xi's count times
  its share :data:`XI_SHARE` (relative to the scenario's largest xi), between the same bounds,
  each a 1 / (number of xi) part of :func:`~g2tom.models.discrete_cost.field_seconds`.
  Without the shares the plan over-predicted the full atlas's 33 scenes 1.7x (median of
  measured / planned 0.59, 0.47-1.37); with them 0.96 (0.67-1.75; interquartile 0.86-1.14);
* a per-step target (``oxide.step_half_width``): every cell's further realizations at its light
  steps (:func:`g2tom.models.discrete_cost.step_fields`, from what alpha's target asks of
  the cell before the ensemble's bounds), in the cube and in the fits' bootstrap.

The constants are one thread's CPU seconds or counts measured on this 2-core machine (2026-11-27,
small fixed ensembles of design scenes d02, d12, d22, d24: mu 7.07 at Pi 5, 40, 320, and mu 50 at
Pi 320; see each constant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.config import Scenario
from g2tom.models import contact_model

__all__ = ["SceneCost", "scene_cost", "discrete_fields", "discrete_xi_fields", "cell_fields"]

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
#: Realizations of each xi over those of the slowest (the largest) xi, at xi 0.1, 0.3, 0.5, 0.7, 0.9
#: (:data:`XI_SHARE_AT`): the medians over the full atlas's 33 scenes (2026-11-27, adaptive, 5 %)
#: and lambda where the slowest xi took 400 realizations or more (at fewer, every xi sits at the
#: minimum); interpolated between, in xi.
XI_SHARE_AT = (0.1, 0.3, 0.5, 0.7, 0.9)
XI_SHARE = (0.14, 0.14, 0.17, 0.28, 1.0)
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
        Discrete pool size at every step (0 on grid spots).
    surfaces_lightest
        The pool's expected size at the lightest step: larger than ``surfaces`` where
        ``contact.pool_half_width`` grows it (the added surfaces' seconds are in ``contact``).
    fields
        Oxide fields of the slowest xi (all lambda; the other xi stop earlier).
    contact, cube, other
        Seconds of the contact stage, of the cube and of the rest (oxide, fits, fixed costs).
    """

    touching: np.ndarray | None
    surfaces: int
    surfaces_lightest: int
    fields: float
    contact: float
    cube: float
    other: float

    @property
    def seconds(self) -> float:
        """The scene's total."""
        return self.contact + self.cube + self.other


def _slowest_fields(scenario: Scenario, touching: np.ndarray, bounded: bool = True) -> np.ndarray:
    """Realizations of the slowest xi per lambda of an adaptive discrete scene (see the module); not
    ``bounded``: what alpha's target asks, before the ensemble's bounds."""
    from g2tom.before_work.plan import control_variate_share

    ox = scenario.oxide
    mid = max(float(touching[touching.size // 2]), 1.0)
    # fewer touching asperities than the reference do not ask for more: at Pi 5 (N_mid 11) the
    # rule asked for 334 and 743 fields at lambda 1 and 23, below the reference's counts
    scale = (min(1.0, (REFERENCE_TOUCHING / mid) ** FIELDS_EXPONENT) * (REFERENCE_TARGET / ox.target_half_width) ** 2
             * control_variate_share(scenario))
    reference = np.interp(np.log(ox.lambda_), np.log([1.0, 3.0, 7.0, 11.0, 17.0, 23.0]), REFERENCE_FIELDS)
    return np.clip(reference * scale, ox.min_realizations, ox.max_realizations) if bounded else reference * scale


def discrete_fields(scenario: Scenario, touching: np.ndarray) -> float:
    """Typical oxide fields of an adaptive discrete scene (the slowest xi's, all lambda; see the
    module), or the fixed count."""
    ox = scenario.oxide
    if ox.ensemble != "adaptive":
        return float(ox.n_realizations * len(ox.lambda_))
    return float(np.sum(_slowest_fields(scenario, touching)))


def cell_fields(scenario: Scenario, touching: np.ndarray, bounded: bool = True) -> np.ndarray:
    """Realizations of every (xi, lambda) of an adaptive discrete scene by alpha's target: the slowest
    xi's (:func:`discrete_fields`) times each xi's share (:data:`XI_SHARE`), within the ensemble's
    bounds (not ``bounded``: what the target asks)."""
    ox = scenario.oxide
    xi = np.asarray(ox.xi, float)
    share = np.interp(xi, XI_SHARE_AT, XI_SHARE) / np.interp(xi.max(), XI_SHARE_AT, XI_SHARE)
    per_xi = _slowest_fields(scenario, touching, bounded)[None, :] * share[:, None]
    return np.clip(per_xi, ox.min_realizations, ox.max_realizations) if bounded else per_xi


def discrete_xi_fields(scenario: Scenario, touching: np.ndarray) -> float:
    """Fields' worth of cube work of a discrete scene: every xi's realizations summed over xi and
    lambda, over the number of xi (:func:`cell_fields`; a fixed ensemble computes every xi of every field)."""
    ox = scenario.oxide
    if ox.ensemble != "adaptive":
        return discrete_fields(scenario, touching)
    return float(cell_fields(scenario, touching).sum() / len(ox.xi))


def scene_cost(scenario: Scenario) -> SceneCost:
    """The modelled CPU seconds of one atlas scene (its scenario as :func:`g2tom.atlas.design.scene_scenario`
    makes it), single-threaded."""
    from g2tom.before_work import plan
    from g2tom.models.discrete_cost import (expected_counts, field_seconds, grown_pool, step_fields,
                                                    surface_seconds)

    if not contact_model(scenario).pooled:  # the lattice's costs, as g2tom plan has them
        estimates = {e.stage: e.seconds for e in plan.estimate(scenario, 1)}
        counts = plan.realizations(scenario)
        return SceneCost(None, 0, 0, counts.fields * len(scenario.oxide.lambda_), estimates["contact"],
                         estimates["cube"], estimates["oxide"] + estimates["fits"] + SCENE_S)
    n, c = expected_counts(scenario)
    sizes, added = grown_pool(scenario, n, c)
    contact = scenario.contact.surfaces * surface_seconds(n, c) + added
    per_field = field_seconds(n, c)
    fields = discrete_fields(scenario, n)
    work = discrete_xi_fields(scenario, n)
    extra, light_seconds = 0.0, 0.0
    if scenario.oxide.ensemble == "adaptive":  # a per-step target's realizations at the light steps
        steps, light_seconds = step_fields(scenario, n, c, cell_fields(scenario, n, bounded=False))
        extra = float(np.sum(steps.mean(axis=-1) - steps[..., -1]))  # the fits' bootstrap runs over each step's own
    cells = len(scenario.oxide.xi) * len(scenario.oxide.lambda_)
    other = (SCENE_S + FITS_S * (fields / len(scenario.oxide.lambda_) * cells + extra)
             * scenario.fits.n_bootstrap / 100)
    return SceneCost(n, scenario.contact.surfaces, int(sizes[0]), fields, contact,
                     per_field * work + light_seconds, other)
