"""What a scene of discrete asperities costs, before any work: Greenwood–Tripp's expected counts
and the cost model of the discrete contact pool and cube.

On discrete asperities (``contact.model = "discrete"``) the cost grows with the count of
touching asperities, not with a cell grid: every surface of the pool is a dense Newton solve over
its touching caps at every load step, and every oxide field a dense point-interaction solve over
the conducting spots at every step. Both are modelled per load step from Greenwood–Tripp's
expected count of touching asperities N_s and of candidates C_s (:func:`expected_counts`, one
fast solve, :func:`probe`; within a few % of the discrete pool's at the heavy steps):

* one surface of the pool: ``sum_s (CONTACT_STEP_S + CONTACT_SQUARE_S C_s^2 + CONTACT_POWER_S
  N_s^2.5)`` (:func:`surface_seconds`), C_s the expected candidates (asperities above the undeformed
  indenter); a grown pool (``contact.pool_half_width``) adds the surfaces :func:`grown_pool` expects,
  each solved up to its last step, plus :data:`ADDED_SURFACE_S` each;
* one oxide field (one realization at one lambda, all its xi at once: the point solves of a step
  share one factorization, or one conjugate-gradient sweep from a union of
  :data:`g2tom.physics.discrete_resistance.ITERATIVE_FROM` spots): ``sum_s (FIELD_STEP_S +
  FIELD_SQUARE_S N_s^2 + FIELD_MIXED_S C_s N_s + FIELD_CUBE_S N_s^3)`` over the factorized steps
  and ``FIELD_ITERATIVE_S N_s^2`` in place of the cube on the others (:func:`field_seconds`).

The constants are one thread's CPU seconds measured on a 2-core machine (2026-11-27, small fixed
ensembles of atlas design scenes d02, d12, d22, d24: mu 7.07 at Pi 5, 40, 320, and mu 50 at Pi 320;
d21 and d20, mu 2.66 and 1 at Pi 320, for the large unions; see each constant). ``g2tom plan`` scales its estimates of the default scene by these models'
ratio (:meth:`g2tom.models.Discrete.plan_work`); ``g2tom plan --atlas`` adds them up per scene
(:mod:`g2tom.atlas.cost`).
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np

from g2tom.config import Scenario

__all__ = ["probe", "expected_counts", "expected_touching", "expected_force_normalized", "surface_seconds",
           "field_seconds", "grown_pool", "step_fields", "DISCRETE_SOLVE_S", "DEFAULT_STEPS", "DISCRETE_XI_MAP_S",
           "DEFAULT_SURFACE_MODEL_S", "DEFAULT_HEAVIEST_TOUCHING", "DEFAULT_FIELD_MODEL_S"]

#: One thread's time per discrete surface and load step of the contact solve (s): the median of
#: `g2tom bench --only discrete` on the paper's scene, 3.85 ms.
DISCRETE_SOLVE_S = 3.85e-3
#: Load steps of the default scene, on which DISCRETE_SOLVE_S and DISCRETE_XI_MAP_S were measured.
DEFAULT_STEPS = 20
#: One thread's time per (xi, field) of the cube on discrete spots (s) by (oxide.spot_rule,
#: cube.model): (disc, point) from the default `make run` from a fresh clone (2026-11-27, 2 cores,
#: compiled point solves and disc shares: the cube took 92.05 s, 2 x 92.05 / 188,200); the
#: (centre, point) pair scaled by the same ratio to the previous code's 5.5 ms (not measured); the
#: Greenwood pairs are the previous code's, whose Greenwood form did not change (not remeasured).
DISCRETE_XI_MAP_S = {("disc", "point"): 2 * 92.05 / 188_200, ("centre", "point"): 3.0e-3 * 2 * 92.05 / 188_200 / 5.5e-3,
                     ("disc", "greenwood"): 2.8e-3, ("centre", "greenwood"): 0.75e-3}
# the segment rule counts shares as disc does (its table lookup is a few % of a field's work)
DISCRETE_XI_MAP_S.update({("segment", model): DISCRETE_XI_MAP_S[("disc", model)] for model in ("point", "greenwood")})
#: The discrete cost models (this module) on the default scene (its
#: 20 steps' expected counts: at most 210 touching asperities and 754 candidates), CPU seconds of
#: one thread: one surface of the pool, one oxide field's point solves (every xi). Another scene's
#: discrete pool and cube are estimated as the default's measured constants above times the
#: models' ratio, so the cost follows the touching count (dense solves: N^2.5 to N^3 at large N).
DEFAULT_SURFACE_MODEL_S = 0.07436773256159718
DEFAULT_HEAVIEST_TOUCHING = 210
DEFAULT_FIELD_MODEL_S = 0.008316928707799072
#: Radial nodes of the fast solve.
_N_RADIAL = 400
#: Rigid gap (units of sigma) at the fast solve's outer radius: f_{3/2}(12) ~ 1e-33 of the peak.
_FAR_GAP = 12.0
#: Contact pool, one surface: seconds per load step, per candidate squared (the coupling kernel
#: over the candidates) and per touching asperity to the power 2.5 (the Newton factorizations:
#: LAPACK runs faster on larger matrices, so a cube overstated large pools), each summed over the
#: steps. Step and square fitted exactly to d12: 0.085 s per surface of 20 steps (candidates <=
#: 832, N <= 249) and d24 (mu 50, Pi 320): 1.94 s (4,792, 469); the power term by least squares in
#: relative error on the contact stage's CPU seconds per surface (2026-11-27): d22 10.1 s (6,657,
#: 1,993), d21 29.1 s (N <= 3,676), d20 80.4 s (6,084), which the model gives as 0.85, 0.94, 1.11.
CONTACT_STEP_S = 2.0e-4
CONTACT_SQUARE_S = 2.15e-8
CONTACT_POWER_S = 5.63e-9
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
#: Cube, one field, a step of N_s >= ITERATIVE_FROM: seconds per N_s^2 of the conjugate-gradient
#: sweeps (about 16, all xi at once, bound by reading the union's kernel), in place of the cube;
#: least squares in relative error on the cube's CPU seconds per field (2026-11-27, 3-16 fields
#: at lambda 1 and 23): d24 58.6 ms (its last steps), d22 0.456 s, d21 2.09 s (N <= 3,676), d20
#: 5.68 s (N <= 6,084); with the factorized steps' constants above the model gives 0.83, 1.22, 0.86
#: and 0.89 of those (d02 and d12: 0.93, 0.90).
FIELD_ITERATIVE_S = 9.49e-9
#: A grown pool: the relative sd of one surface's K at a step, modelled as
#: ``POOL_SCATTER sqrt(M) / (M + POOL_SCATTER_KNEE)`` with ``M = N_s + 1`` (a surface touches on at
#: least the one cap that carries the force; with a single cap K depends only on the force). Set to
#: the contact stage of two held-out atlas scenes (2026-11-28): h06 (mu 4.3, Pi 156) measured 0.242,
#: 0.169, 0.116, 0.084 at its four lightest steps (N 10-62; the model 0.24, 0.19, 0.15, 0.12) and h07
#: (mu 26, Pi 7.5) 0.16-0.20 at N 0.1-2.4 (the model 0.26-0.28): up to 1.5x high, 2x in surfaces.
POOL_SCATTER = 1.0
POOL_SCATTER_KNEE = 3.0
#: Seconds per added surface besides its solves (drawing its asperities on the heaviest step's disc
#: and ordering them): h06's 531 added surfaces took 5.6 s more than its 39 (2026-11-28).
ADDED_SURFACE_S = 0.01
#: A per-step target (``oxide.step_half_width``): the 95 % relative half-width of one load step's
#: geometric mean of R over alpha's at the same realizations, by F' (:data:`STEP_RATIO_AT`;
#: interpolated in ln F', constant beyond): the medians over the 25 design scenes of the atlas of
#: 2026-11-27 (mu 1-50, Pi 5-320, every (xi, lambda); the upper quartile is 1.2-2x these). The light
#: steps are the noisy ones: their few touching spots, and alpha's fit averages 20 steps.
STEP_RATIO_AT = (0.049, 0.111, 0.232, 0.44, 0.763, 1.218, 1.814, 2.551, 4.429, 8.161, 20.4)
STEP_RATIO = (3.53, 2.8, 2.3, 2.1, 1.49, 1.17, 0.92, 0.72, 0.53, 0.38, 0.23)
#: Seconds of one cell's oxide field computed at a prefix of the steps besides the steps' own
#: (:func:`field_seconds`): drawing its coefficients and the field at the spots' discs. Measured on
#: design scenes d02, d12 and d22 (2026-11-28, 40 fields at lambda 1 and 23, at the first 1 and 3
#: steps, with the atlas computing beside it): 0.6-2.3 ms per field, 0.1-0.4 ms of it modelled.
FIELD_PREFIX_S = 1.0e-3
#: The expected touching and candidate counts and F' found so far, by the parameters that set them.
_COUNTS: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def probe(scenario: Scenario, delta_sigma: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A fast Greenwood–Tripp solve at the approaches ``delta_sigma`` (units of sigma, lightest
    first, evenly spaced), warm-started along them: radial nodes (m) and the contact stage's fields
    (:func:`g2tom.contact_solution.fields`: separation ``h``, pressure ``p``, ``force``, ...).

    Parameters
    ----------
    scenario
        The surface, sphere and material (its loading and domains are replaced).
    delta_sigma
        Approaches delta / sigma, decreasing (negative: interpenetration).

    Raises
    ------
    ValueError
        If the approaches are not evenly spaced and decreasing.
    """
    from g2tom.contact_solution import fields, indenter_profile, solve

    deltas = np.atleast_1d(np.asarray(delta_sigma, float))
    sigma = scenario.roughness.sigma
    r = scenario.indenter.radius * 1e-6
    while (deltas.min() * sigma + float(indenter_profile(scenario, np.array([r]))[0])) < _FAR_GAP * sigma:
        r *= 1.5
    probe_scenario = Scenario.of(
        scenario,
        loading=dataclasses.replace(scenario.loading, delta_max=float(deltas[0]), delta_min=float(deltas[-1]),
                                    n_delta=deltas.size),
        contact=dataclasses.replace(scenario.contact, r_max=r / scenario.indenter.radius, window=1.0,
                                    radial_grid="graded", n_radial=_N_RADIAL, solver="newton"))
    if not np.allclose(np.array(probe_scenario.deltas) / sigma, deltas, rtol=0, atol=1e-9):
        raise ValueError("the approaches must be evenly spaced and decreasing")
    nodes, sols = solve(probe_scenario, tolerance=1e-10)
    return nodes, fields(probe_scenario, nodes, sols)


def expected_counts(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Greenwood–Tripp's expected count of touching asperities at each of the scenario's
    approaches, 2 pi eta integral P(z > h(r)) r dr with h the solved separation (z ~ N(0, sigma^2)),
    and of candidates, the asperities above the undeformed indenter (h the rigid gap: the discrete
    solve's candidate set, displacements only lowering asperities), by one fast solve."""
    from scipy.special import erfc

    from g2tom.contact_solution import indenter_profile
    from g2tom.physics.greenwood_tripp import force_weights

    key = _counts_key(scenario)
    if key not in _COUNTS:
        sigma = scenario.roughness.sigma
        deltas = np.asarray(scenario.deltas)
        nodes, solved = probe(scenario, deltas / sigma)
        weights = scenario.roughness.eta * force_weights(nodes)
        rigid = deltas[:, None] + indenter_profile(scenario, nodes)[None, :]
        counts = tuple(0.5 * erfc(gap / (sigma * math.sqrt(2.0))) @ weights for gap in (solved["h"], rigid))
        _COUNTS[key] = (*counts, np.asarray(solved["force"], float) / scenario.force_scale)
    return _COUNTS[key][0].copy(), _COUNTS[key][1].copy()


def expected_force_normalized(scenario: Scenario) -> np.ndarray:
    """F' of Greenwood–Tripp's fast solve at each of the scenario's approaches (:func:`expected_counts`'s)."""
    expected_counts(scenario)
    return _COUNTS[_counts_key(scenario)][2].copy()


def _counts_key(scenario: Scenario) -> str:
    """The parameters that set :func:`expected_counts`'s solve, as its cache key."""
    return json.dumps({k: v for k, v in scenario.flat().items()
                       if k.startswith(("material.", "roughness.", "indenter.", "loading."))}, sort_keys=True)


def expected_touching(scenario: Scenario) -> np.ndarray:
    """Greenwood–Tripp's expected count of touching asperities at each approach (:func:`expected_counts`)."""
    return expected_counts(scenario)[0]


def surface_seconds(touching: np.ndarray, candidates: np.ndarray) -> float:
    """Modelled CPU seconds (one thread) of one surface of the discrete pool over its load steps.

    Parameters
    ----------
    touching, candidates
        (steps,) expected touching asperities and candidates per load step (:func:`expected_counts`).
    """
    return (CONTACT_STEP_S * touching.size + CONTACT_SQUARE_S * float(np.sum(candidates**2))
            + CONTACT_POWER_S * float(np.sum(touching**2.5)))


def field_seconds(touching: np.ndarray, candidates: np.ndarray) -> float:
    """Modelled CPU seconds (one thread) of one oxide field's point solves over the load steps, every xi.

    Parameters
    ----------
    touching, candidates
        (steps,) expected touching asperities and candidates per load step (:func:`expected_counts`).
    """
    from g2tom.physics.discrete_resistance import ITERATIVE_FROM  # numba: only where a field is costed

    factorized = touching < ITERATIVE_FROM
    return (FIELD_STEP_S * touching.size + FIELD_SQUARE_S * float(np.sum(touching**2))
            + FIELD_MIXED_S * float(np.sum(candidates * touching))
            + FIELD_CUBE_S * float(np.sum(touching[factorized]**3))
            + FIELD_ITERATIVE_S * float(np.sum(touching[~factorized]**2)))


def grown_pool(scenario: Scenario, touching: np.ndarray, candidates: np.ndarray) -> tuple[np.ndarray, float]:
    """The pool a scenario's ``contact.pool_half_width`` is expected to grow, and what it adds.

    Parameters
    ----------
    scenario
        Its ``contact.surfaces``, ``contact.pool_half_width`` (0: the fixed pool).
    touching, candidates
        (steps,) expected touching asperities and candidates per load step (:func:`expected_counts`).

    Returns
    -------
    tuple
        The expected pool size per step, (steps,), and the modelled CPU seconds (one thread) of the
        surfaces beyond ``contact.surfaces``, each solved up to the last step that still needs it.
    """
    from g2tom.config import MAX_POOL_SURFACES, POOL_CONFIDENCE
    from g2tom.fitting.ensemble import z_value

    fixed, target = scenario.contact.surfaces, scenario.contact.pool_half_width
    if target <= 0:
        return np.full(touching.size, fixed), 0.0
    m = np.asarray(touching, float) + 1.0
    scatter = POOL_SCATTER * np.sqrt(m) / (m + POOL_SCATTER_KNEE)
    wanted = np.ceil((z_value(POOL_CONFIDENCE) * scatter / target) ** 2)
    # the stage grows a prefix of the steps: a step is solved on at least the surfaces any heavier one needs
    sizes = np.clip(np.maximum.accumulate(wanted[::-1])[::-1], fixed, max(fixed, MAX_POOL_SURFACES)).astype(int)
    seconds = 0.0
    for steps in range(1, touching.size + 1):  # surfaces solved at exactly the first `steps` steps
        added = sizes[steps - 1] - (sizes[steps] if steps < touching.size else fixed)
        if added > 0:
            seconds += added * (ADDED_SURFACE_S + surface_seconds(touching[:steps], candidates[:steps]))
    return sizes, seconds


def step_fields(scenario: Scenario, touching: np.ndarray, candidates: np.ndarray,
                needed: np.ndarray) -> tuple[np.ndarray, float]:
    """The realizations a per-step target (``oxide.step_half_width``) is expected to add, and their cost.

    A fitted step's half-width is :data:`STEP_RATIO` times alpha's at the same realizations, so where
    alpha's target asks ``needed`` realizations the step asks ``needed (ratio target / step target)^2``: at
    least alpha's count (``needed`` within the ensemble's bounds), at most ``oxide.max_realizations``,
    each step at least what a heavier one asks; a realization past alpha's count is computed up to
    the heaviest step that still needs it.

    Parameters
    ----------
    scenario
        Its ``oxide`` targets and bounds, its loading (the steps' F', :func:`expected_force_normalized`).
    touching, candidates
        (steps,) expected touching asperities and candidates per load step (:func:`expected_counts`).
    needed
        The realizations alpha's target asks in each cell (xi, lambda), before the ensemble's bounds;
        any shape.

    Returns
    -------
    tuple
        Each cell's expected realizations at every step (``needed``'s shape, steps), and the modelled
        CPU seconds (one thread) of all cells' realizations past alpha's count: per realization
        :data:`FIELD_PREFIX_S` and a ``1 / n_xi`` part of :func:`field_seconds` over its steps.
    """
    ox = scenario.oxide
    needed = np.asarray(needed, float)[..., None]
    alpha = np.clip(needed, ox.min_realizations, ox.max_realizations)
    if ox.ensemble != "adaptive" or ox.step_half_width <= 0:
        return np.repeat(alpha, touching.size, axis=-1), 0.0
    force = expected_force_normalized(scenario)
    _, threshold, loads, _ = scenario.fits.fitted_loads(force * scenario.force_scale, force)
    ratio = np.interp(np.log(np.maximum(force, 1e-300)), np.log(STEP_RATIO_AT), STEP_RATIO)
    asked = np.where(loads >= threshold, (ratio * ox.target_half_width / ox.step_half_width) ** 2, 0.0)
    wanted = np.maximum.accumulate(asked[::-1])[::-1]  # only fitted steps have a target
    counts = np.clip(needed * wanted, alpha, ox.max_realizations)
    prefix = [FIELD_PREFIX_S + field_seconds(touching[:m], candidates[:m]) / len(ox.xi)
              for m in range(1, touching.size + 1)]
    beyond = counts - np.concatenate([counts[..., 1:], alpha], axis=-1)  # computed at exactly m steps
    return counts, float(np.sum(np.maximum(beyond, 0.0) * np.array(prefix)))
