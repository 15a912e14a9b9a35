"""Resources known before work: peak memory and run time of each stage, from the parameters.

:func:`estimate` models each stage's largest arrays (the stored results and the work arrays
of its concurrently running tasks) and its run time (flop-count models with constants
measured on the 2-core reference machine; ``make bench`` measures the real ones).
The checks that refuse a run on these estimates are :mod:`g2tom.before_work.resources`'.
An adaptive ensemble's realization count is known only after the work, so its estimates
carry a range (every cell stopped at ``oxide.min_realizations`` .. every cell at the cap
``oxide.max_realizations``) and a central value typical of the paper's scene
(:func:`realizations`); memory is checked at the typical counts (a run refused), and at the
cap, the padded realization axis the cube and fits hold in the worst case (a warning).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from g2tom.config import AUTO, CHUNK_BYTES, ResolvedScenario, Scenario, odd_cells

__all__ = ["StageEstimate", "Realizations", "realizations", "estimate", "format_plan", "available_memory", "BASE_BYTES"]

#: Resident memory of a g2tom stage's process with its small arrays: the surrogate stage of the
#: default run peaked at 217 MiB (process tree, sampled every 0.1 s; 2026-11-25).
BASE_BYTES = 210 * 2**20
#: Seconds per flop-like unit of the models below (measured on the reference machine, one thread).
_FOLDED_S = 1.35e-10  # per n^3 of one folded map (fixed 400-realization cubes of the paper's scene on one
                      # thread: 864,000 maps in 26.1 s at 55^2 cells, 18.7 s at 49^2, fields apart)
_FFT_S = 3.2e-10      # per P^2 log2 P of one FFT map (ducc0, blocks of 2; fitted to the 229^2 study's
                      # cube, 410 s on two threads: 0.76 ms per map and thread with _MAP_S)
_MAP_S = 2.0e-9       # per cell of one map (masking, sums), any path
_LU_S = 5.0e-11       # per n_radial^3 and approach (Newton factorizations and solves)
_MODE_S = 4.0e-8      # per mode and realization of the oxide coefficients
_CELL_FFT_S = 5.0e-9  # per n^2 log2 n of one oxide field
TYPICAL_TARGET = 0.025
#: Realizations the adaptive ensemble needs with ``fits.control_variate = "clean_share"``, as a share
#: of the plain rule's: measured on the atlas's held-out scene h02 (mu 22.4, Pi 28.6; 5 xi x 6
#: lambda), the fields over lambda summed: 1,224 / 4,234 at target 5 % and 4,847 / 15,868 at 2.5 %.
CONTROL_VARIATE_REALIZATIONS = 0.3
#: Stage times of the two default studies measured on 2026-11-27 (2 cores; each stage run by
#: `g2tom STAGE --no-progress` in a fresh data directory, the seconds it reports) over what the
#: models below give for them: contact 0.95 s (paper_gt) over 0.604 s, the discrete pool's part
#: being DISCRETE_SOLVE_S's (11.07 s for `paper`); oxide 1.30 s and 0.84 s (the same oxide stage,
#: two windows) over 1.14 s; fits 9.89 s (paper_gt, 361,115 realizations) over 0.578 s and 4.92 s
#: (paper, 146,587) over 0.2345 s, their geometric mean; the surrogate 3.31 s and 3.60 s over its
#: 108 cells (the joint fit's cross-validated order search grows with the grid). The previous
#: calibration (2026-11-25: 2.12, 2.27, 17.4 and 11.6 s for paper_gt) was 1.7-3.5x over today's.
CONTACT_CALIBRATION = 0.95 / 0.604
OXIDE_CALIBRATION = (1.30 + 0.84) / 2 / 1.14
FITS_CALIBRATION = (9.89 / 0.578 * 4.92 / 0.2345) ** 0.5
SURROGATE_SECONDS_PER_CELL = (3.31 + 3.60) / 2 / 108
#: The fits stage with ``fits.control_variate = "clean_share"`` over the model above for its
#: realizations: the default study's 2.83 s (median of three, 2026-11-29, 60,885 realizations)
#: over the 1.333 s the model gives (each bootstrap resample's controlled mean takes three
#: weighted moments more, and the stage's fixed work weighs more on the fewer realizations).
CONTROL_VARIATE_FITS_CALIBRATION = 2.83 / 1.333
#: The fits stage's peak resident memory in the default run (2,812 MiB, process tree sampled every
#: 0.1 s, 2026-11-25) less BASE_BYTES, over what the model gives for it (7,527 MiB: the model
#: counts three full copies of the results where the bootstrap holds about one).
FITS_MEMORY_CALIBRATION = (2812 - 210) / 7527
#: Copies of the cube's results (five float64 terms on the padded axis) at its peak: the default
#: run peaked at 3,470 MiB (process tree with its two workers, 2026-11-25), i.e. its 2,470 MiB of
#: results 1.27 times over the 210 + 119 MiB of the rest (the model said 2 copies).
CUBE_RESULT_COPIES = (3470 - 210 - 119) / 2470
#: Speed-up of the local threaded scheduler over one thread on folded maps (small windows),
#: measured on 2 cores on the paper's scene (49^2 cells): a fixed 400-realization cube took 18.7 s
#: on one thread and 12.1 s on two; the adaptive default 164.5 s for 196.5 s of CPU (its late
#: rounds hold few tasks and end in a serial decision). Beyond two threads it is not measured.
THREADED_FOLDED_SPEEDUP = {"fixed": 18.71 / 12.09, "adaptive": 196.5 / 164.5}


@dataclass(frozen=True)
class StageEstimate:
    """Estimated peak resident memory (bytes) and wall time (s) of one stage."""

    stage: str
    peak_bytes: float
    seconds: float
    #: Run-time range (s) of an adaptive ensemble: all cells at min_realizations .. at the cap.
    seconds_range: tuple[float, float] | None = None
    #: Peak memory (bytes) of an adaptive ensemble if a cell ran to oxide.max_realizations.
    peak_bytes_cap: float | None = None


@dataclass(frozen=True)
class Realizations:
    """Realizations per (xi, lambda): the fewest, the most and the central (typical) count.

    ``computed`` is the typical count the cube evaluates per (xi, lambda) (whole batches),
    ``fields`` the typical count of fields it generates per lambda and ``largest`` the typical
    largest count over the cells (the cube's padded realization axis, which sets the cube's and
    the fits' memory); all are ``low`` and ``high`` at the ends of the range.
    """

    low: int
    typical: float
    high: int
    adaptive: bool
    computed: float
    fields: float
    largest: float


def control_variate_share(scenario: Scenario) -> float:
    """The adaptive ensemble's realizations with the scenario's control variate against without it
    (:data:`CONTROL_VARIATE_REALIZATIONS`; 1 without one)."""
    return CONTROL_VARIATE_REALIZATIONS if scenario.fits.control_variate == "clean_share" else 1.0


def realizations(scenario: Scenario) -> Realizations:
    """The realization counts per (xi, lambda) a run can use.

    A fixed ensemble uses ``oxide.n_realizations``. An adaptive one uses between
    ``oxide.min_realizations`` and ``oxide.max_realizations``; the central value is
    the contact model's typical count (:attr:`g2tom.models.ContactModel.typical`, measured on the paper's scene) scaled by
    ``(TYPICAL_TARGET / oxide.target_half_width)^2`` (a half-width falls like n^-1/2) and by the
    control variate's share (:func:`control_variate_share`), clipped to that range. It is a typical value on the paper's scene, not a prediction for any scene.
    """
    ox = scenario.oxide
    if ox.ensemble != "adaptive":
        n = ox.n_realizations
        return Realizations(n, float(n), n, False, float(n), float(n), float(n))
    scale = (TYPICAL_TARGET / ox.target_half_width) ** 2 * control_variate_share(scenario)

    def clip(value: float) -> float:
        return min(max(value * scale, ox.min_realizations), ox.max_realizations)

    from g2tom.models import contact_model  # here: the command line imports this module before numpy

    typical = contact_model(scenario).typical
    return Realizations(ox.min_realizations, clip(typical.realizations), ox.max_realizations, True,
                        clip(typical.computed), clip(typical.fields), clip(typical.largest))


def available_memory() -> float:
    """Memory this machine can give a run, in bytes (psutil's ``available``: ``MemAvailable`` on Linux;
    also on Windows and macOS)."""
    import psutil

    return float(psutil.virtual_memory().available)


def _cells(scenario: Scenario) -> int:
    """Cells per window side: the explicit or resolved window's, or a cheap estimate while ``auto``."""
    if scenario.contact.window != AUTO:
        return odd_cells(float(scenario.contact.window) * scenario.indenter.radius, scenario.cell_size)
    from g2tom.before_work.domains import estimate_cells

    return estimate_cells(scenario)


def _modes(scenario: Scenario, n: int, lam: float) -> float:
    """Lattice wave vectors of the oxide band of ``lam`` (half plane, k1 = n / (2 lambda), at
    least oxide.spectral_resolution with the spectral period)."""
    k1 = n / (2.0 * lam)
    if scenario.oxide.period == "spectral":
        k1 = max(k1, scenario.oxide.spectral_resolution)
    return 0.5 * math.pi * k1 * k1 * (scenario.oxide.ks_ratio**2 - 1.0) + 4.0 * k1 * scenario.oxide.ks_ratio


def _max_modes(scenario: Scenario, n: int) -> float:
    """Lattice wave vectors of the largest oxide band."""
    return _modes(scenario, n, min(scenario.oxide.lambda_))


def _field_seconds(scenario: Scenario, n: int) -> float:
    """One thread's time for one field of each lambda in turn (s)."""
    fft = _CELL_FFT_S * n * n * math.log2(max(n, 2))
    return sum(_MODE_S * _modes(scenario, n, lam) + fft for lam in scenario.oxide.lambda_)


def _per_map_seconds(n: int) -> float:
    from g2tom.physics.interaction import auto_method
    from g2tom.physics.interaction_fft import padded_length

    if auto_method(n) == "folded":
        return _FOLDED_S * n**3 + _MAP_S * n * n
    p = padded_length(n)
    return _FFT_S * p * p * math.log2(p) + _MAP_S * n * n


def _threads(workers: int | None) -> int:
    return max(1, workers or os.cpu_count() or 1)


def _map_speedup(n: int, workers: int | None, ensemble: str) -> float:
    """Speed-up of the cube's maps over one thread: local processes and the threaded scheduler
    on FFT maps (whose constant was fitted on two threads) scale with the workers; the threaded
    scheduler on folded maps by :data:`THREADED_FOLDED_SPEEDUP` (measured)."""
    from g2tom.compute import _distributed_available
    from g2tom.physics.interaction import auto_method

    if _threads(workers) == 1:
        return 1.0
    processes = workers is not None and workers > 1 and _distributed_available()  # as g2tom.compute
    if processes or auto_method(n) != "folded":
        return float(_threads(workers))
    return min(float(_threads(workers)), THREADED_FOLDED_SPEEDUP[ensemble])


def estimate(scenario: Scenario, workers: int | None = None) -> list[StageEstimate]:
    """Peak memory and run time of every stage of ``scenario``.

    Parameters
    ----------
    scenario
        Resolved or not (``auto`` windows are estimated from the rigid gap).
    workers
        Concurrent tasks (default: the core count).

    Returns
    -------
    list of StageEstimate
        contact, oxide, cube, fits, surrogate, in order.
    """
    from g2tom.models import PlanWork, contact_model
    from g2tom.physics.interaction import FFT_FROM, block_size, work_bytes_per_map
    from g2tom.physics.interaction_fft import padded_length

    n = _cells(scenario)
    cells = float(n) * n
    ox, t = scenario.oxide, _threads(workers)
    n_xi, n_lam, n_real = len(ox.xi), len(ox.lambda_), ox.n_realizations  # n_real: fields in oxide.nc
    counts = realizations(scenario)
    n_cube, n_cap = counts.largest, counts.high  # the cube's padded realization axis: typical, at the cap
    n_delta, n_r = scenario.loading.n_delta, scenario.contact.n_radial
    # contact: influence matrix and its Newton copies; spot maps over delta; the resolve grid.
    contact_mem = 8.0 * (7 * n_r * n_r + 10 * n_delta * cells + 8 * 4 * cells)
    contact_s = CONTACT_CALIBRATION * (_LU_S * n_r**3 * (1 + n_delta) + 4e-7 * n_r * n_r + 1e-7 * n_delta * cells)
    # oxide: psi (float32) held whole (chunks are copied in as they come); per task a chunk's
    # fields and the complex spectra of their synthesis; the band's lattice and coefficients.
    psi = 4.0 * n_lam * n_real * cells
    modes = _max_modes(scenario, n)
    chunk = min(scenario.compute.oxide_chunk, n_real, max(1, int(CHUNK_BYTES // (4.0 * n_lam * cells))))
    task_ox = chunk * cells * (4.0 * n_lam + 24.0) + 64.0 * modes
    oxide_mem = psi + t * task_ox + 48.0 * modes
    oxide_s = OXIDE_CALIBRATION * n_lam * n_real * (_MODE_S * modes + _CELL_FFT_S * cells * math.log2(max(n, 2))) / t
    # cube: psi read whole, per task the masks and one block of work, the cached operators,
    # the results (five float64 terms, concatenated once). Measured on the 583^2 scene
    # (2 xi x 2 lambda x 50): contact 767 MiB, oxide 953 MiB, cube 1215 MiB peak RSS.
    def results_of(n_axis: float) -> float:
        return 8.0 * 5 * n_xi * n_lam * n_delta * n_axis

    block = block_size(n)
    task_cube = n_xi * n_lam * min(scenario.compute.cube_chunk, n_cube) * cells * 1.0 + block * (
        work_bytes_per_map(n) + 9.0 * cells)
    if n < FFT_FROM:
        operators = min(n_delta, 32) * 4.0 * n**3
    else:
        p = padded_length(n)
        operators = n_delta * 8.0 * p * p  # the cached interleaved spectrum, one per crop size
    # contact's spot maps: read (radius, area) and as float64 maps, and three per-task copies
    spot_maps = 8.0 * n_delta * cells
    cube_fixed = psi + t * (task_cube + 3 * spot_maps) + 4 * spot_maps + operators
    # the maps of every computed realization (whole batches) and the fields regenerated per lambda
    speedup = _map_speedup(n, workers, ox.ensemble)
    per_map = n_xi * n_lam * n_delta * _per_map_seconds(n) / speedup
    per_field = _field_seconds(scenario, n) / speedup
    per_realization = per_map + per_field
    cube_s = per_map * counts.computed + per_field * counts.fields
    # the contact model's own terms (the discrete model's pool and dense solves)
    work = contact_model(scenario).plan_work(scenario, t, counts.typical, counts.computed, PlanWork(
        contact_s, contact_mem, per_realization, cube_s, cube_fixed, n_cube))
    contact_s, contact_mem, per_realization = work.contact_seconds, work.contact_bytes, work.realization_seconds
    cube_s, cube_fixed, n_cube = work.cube_seconds, work.cube_fixed_bytes, work.cube_realizations
    results = results_of(n_cube)
    cube_mem = cube_fixed + CUBE_RESULT_COPIES * results
    # fits: the cube's terms, the bootstrap's resample counts and means.
    boot = scenario.fits.n_bootstrap
    def fits_mem_of(n_axis: float) -> float:
        return FITS_MEMORY_CALIBRATION * (3.0 * results_of(n_axis) + 8.0 * boot * (n_axis + 3 * n_xi * n_lam * n_delta))

    fits_mem = fits_mem_of(n_cube)
    fits_per_realization = FITS_CALIBRATION * 1e-8 * n_xi * n_lam * n_delta * boot / 50
    if scenario.fits.control_variate == "clean_share":
        fits_per_realization *= CONTROL_VARIATE_FITS_CALIBRATION
    fits_s = fits_per_realization * counts.typical

    def spread(per: float) -> tuple[float, float] | None:
        return (per * counts.low, per * counts.high) if counts.adaptive else None

    surrogate_mem = 8.0 * 64 * n_xi * n_lam
    return [
        StageEstimate("contact", BASE_BYTES + contact_mem, contact_s),
        StageEstimate("oxide", BASE_BYTES + oxide_mem, oxide_s),
        StageEstimate("cube", BASE_BYTES + cube_mem, cube_s, spread(per_realization),
                      BASE_BYTES + cube_fixed + CUBE_RESULT_COPIES * results_of(n_cap) if counts.adaptive else None),
        StageEstimate("fits", BASE_BYTES + fits_mem, fits_s, spread(fits_per_realization),
                      BASE_BYTES + fits_mem_of(n_cap) if counts.adaptive else None),
        StageEstimate("surrogate", BASE_BYTES + surrogate_mem, SURROGATE_SECONDS_PER_CELL * n_xi * n_lam),
    ]


def format_plan(scenario: ResolvedScenario, workers: int | None = None) -> list[str]:
    """Lines of ``g2tom plan``: the resolved domains and each stage's estimate."""
    n = scenario.n_cells
    ox = scenario.oxide
    counts = realizations(scenario)
    n_cells = len(ox.xi) * len(ox.lambda_)
    if counts.adaptive:
        ensemble = (f"{counts.low} .. {counts.high} realizations per (xi, lambda) (adaptive), "
                    f"typical {counts.typical:.0f}")
    else:
        ensemble = f"{counts.typical:.0f} realizations"
    from g2tom.models import contact_model  # here: the command line imports this module before numpy

    model = contact_model(scenario)
    lines = [
        f"scenario {scenario.name}: {n} x {n} cells of {scenario.cell_size * 1e6:.4g} um, "
        f"window {scenario.contact.window:.4g} R*, r_max {scenario.contact.r_max:.4g} R*",
        f"{len(ox.xi)} xi x {len(ox.lambda_)} lambda x {scenario.loading.n_delta} "
        f"delta x {ensemble}, {_threads(workers)} workers, {available_memory() / 2**30:.3g} GiB available",
    ]
    if counts.adaptive:
        lines.append(
            f"adaptive ensemble: {counts.low * n_cells} .. {counts.high * n_cells} realizations in all, typical "
            f"{counts.typical * n_cells:.0f} (the paper's scene: "
            f"{model.typical.realizations * 108:.0f} at "
            f"target_half_width {TYPICAL_TARGET:g}, scaled by (target ratio)^2), computed in whole batches: "
            f"typical {counts.computed * n_cells:.0f}; times below are typical "
            f"(range: every cell at oxide.min_realizations .. at oxide.max_realizations); so is memory "
            f"(in brackets: a cell at oxide.max_realizations)")
    from g2tom.scene import scene_plasticity  # here: the command line imports this module before numpy

    plastic = scene_plasticity(scenario)
    lines.append(plastic.line(scenario.roughness.sigma))
    if plastic.hardness is not None:
        lines.append("capped caps: the times below are the elastic caps' cost models; caps that flatten and share "
                     "their discs take longer (on 2 cores: gold_connector, psi 4.5, contact 55 s and cube 193 s, planned "
                     "7.9 s and 36 s; the paper's scene with hardness 2e9, psi 47, contact 204 s, planned 10.8 s), "
                     "and the ensemble may need more realizations than typical where few caps touch")
    lines += model.plan_lines(scenario)
    lines.append(f"{'stage':10s} {'peak memory':>14s} {'time':>12s}")
    total, low, high = 0.0, 0.0, 0.0
    for e in estimate(scenario, workers):
        lo, hi = e.seconds_range or (e.seconds, e.seconds)
        total, low, high = total + e.seconds, low + lo, high + hi
        span = f"   ({lo:.3g} .. {hi:.3g} s)" if e.seconds_range else ""
        cap = (f"   [{e.peak_bytes_cap / 2**20:.0f} MiB]"
               if e.peak_bytes_cap is not None and e.peak_bytes_cap > e.peak_bytes else "")
        lines.append(f"{e.stage:10s} {e.peak_bytes / 2**20:11.0f} MiB {e.seconds:10.3g} s{span}{cap}")
    span = f"   ({low:.3g} .. {high:.3g} s)" if counts.adaptive else ""
    lines.append(f"{'total':10s} {'':>14s} {total:10.3g} s{span} (model constants measured on a 2-core machine)")
    return lines
