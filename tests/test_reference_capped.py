"""The hardness-capped full field (the perfectly plastic surface, 0 <= p <= H) on g2tom's own solver:
against tamaas' KatoSaturated, its two limits (H -> infinity, Holm's plastic spot far above first
yield) and below first yield, where the cap changes nothing; Barber's theorem after plastic loading
(the unloading stiffness) and validate's cases capped at the validated scenario's hardness.

The ``gpu`` test needs CuPy and a device; elsewhere it skips, saying why.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings

import numpy as np
import pytest

from g2tom.config import ConfigError
from g2tom.physics.cap_law import CappedCap
from g2tom.physics.plasticity import yield_force
from g2tom.reference import cases, devices, elastic, scene, surfaces, validate
from g2tom.reference.contact import contact_at_force, flattened_heights
from g2tom.reference.fft_surface import fft_surface
from g2tom.reference.polonsky_keer import MEAN_TOLERANCE, project_onto_box, solve_capped_at_mean_pressure
from g2tom.reference.punch import punch_conductance
from g2tom.scene import FieldSource
from tests.test_reference_fft import _rough_sphere

E_STAR, RHO = 1.154e11, 7.2e-7
GPU_MISSING = devices.gpu_missing()
gpu = pytest.mark.skipif(GPU_MISSING is not None, reason=f"no GPU to test on: {GPU_MISSING}")


def _kato_saturated(heights: np.ndarray, pixel: float, force: float, hardness: float) -> np.ndarray:
    """tamaas' KatoSaturated on its non-periodic operator (as elastic.free_surface registers it), Pa.

    In SI magnitudes (E* 1e11 Pa, a millimetre grid) tamaas 2.9's KatoSaturated stalls at its start
    (its error never moves), so it solves in units of the grid's side and E* (the problem is
    linear in the pressure and scales with the length), to tamaas' error 1e-12.
    """
    import tamaas as tm

    tm.set_log_level(tm.LogLevel.error)
    n = heights.shape[0]
    side = n * pixel
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [1.0, 1.0], [n, n])
    model.E = 1.0  # before registerNonPeriodic, which copies it
    model.nu = 0.0
    tm.ModelFactory.registerNonPeriodic(model, "boussinesq_non_periodic")
    solver = tm.KatoSaturated(model, np.ascontiguousarray(heights / side), 1e-12, hardness / E_STAR)
    solver.setIntegralOperator("boussinesq_non_periodic")
    solver.max_iter = 100_000
    solver.solve(force / side**2 / E_STAR)
    return np.array(model.traction, dtype=float) * E_STAR


def _hertz_sphere(n: int = 64) -> tuple[np.ndarray, float, float, float]:
    """A smooth sphere (R 5 mm) on an ``n``^2 grid of a 1 mm window: heights (m), pixel (m), the force
    (N) of a Hertz contact of radius a quarter of the window and its Hertz peak pressure (Pa)."""
    side, radius = 1e-3, 5e-3
    pixel = side / n
    a = 0.25 * side
    force = 4.0 * E_STAR * a**3 / (3.0 * radius)
    return surfaces.sphere(n, pixel, radius), pixel, force, 3.0 * force / (2.0 * math.pi * a**2)


def _cases() -> list[tuple[np.ndarray, float, float, float]]:
    """(heights, pixel, force, hardness): a smooth sphere capped at 0.6 of its Hertz peak (64^2) and a
    rough sphere at 300 N capped at 10 GPa, a fifth of its elastic peak (96^2, 371 of 403 pixels at H)."""
    heights, pixel, force, peak = _hertz_sphere()
    rough, rough_pixel = _rough_sphere(96)
    return [(heights, pixel, force, 0.6 * peak), (rough, rough_pixel, 300.0, 1e10)]


@pytest.mark.parametrize("case", range(2), ids=["sphere", "rough"])
def test_the_capped_solve_equals_tamaas_kato_saturated(case) -> None:
    heights, pixel, force, hardness = _cases()[case]
    theirs = _kato_saturated(heights, pixel, force, hardness)
    ours = contact_at_force(fft_surface(heights.shape[0], pixel, E_STAR, np), heights, force, 1e-12,
                            hardness=hardness)
    peak = theirs.max()
    assert peak == pytest.approx(hardness, rel=1e-12)  # the cap binds
    assert np.abs(ours.pressure - theirs).max() < 1e-6 * peak  # measured 2e-9 (rough), 8e-10 (sphere)
    assert ours.force == pytest.approx(theirs.sum() * pixel**2, rel=1e-6)
    assert np.count_nonzero(ours.contact != (theirs > 0)) <= 2  # measured 0
    assert np.count_nonzero((ours.pressure == hardness) != (theirs >= hardness * (1 - 1e-12))) <= 2  # measured 0
    assert (ours.pressure == hardness).sum() > 0.5 * ours.contact.sum()
    assert ours.pressure.min() >= 0.0 and ours.pressure.max() == hardness


def test_an_unbounded_hardness_gives_the_elastic_solve() -> None:
    heights, pixel = _rough_sphere()
    operator = fft_surface(heights.shape[0], pixel, E_STAR, np)
    free = contact_at_force(operator, heights, 300.0, 1e-12)
    peak = free.pressure.max()
    capped = contact_at_force(fft_surface(heights.shape[0], pixel, E_STAR, np), heights, 300.0, 1e-12,
                              hardness=1e6 * peak)
    assert np.abs(capped.pressure - free.pressure).max() < 1e-6 * peak
    np.testing.assert_array_equal(capped.contact, free.contact)
    assert capped.force == pytest.approx(free.force, rel=1e-12)
    assert capped.delta == pytest.approx(free.delta, rel=1e-8)


def test_below_first_yield_the_cap_changes_nothing() -> None:
    """H above the Hertz peak: no pixel reaches it and the bounded solve is the elastic one (started from
    it on the same operator, and from a uniform pressure on a fresh one)."""
    heights, pixel, force, peak = _hertz_sphere(128)
    operator = fft_surface(128, pixel, E_STAR, np)
    free = contact_at_force(operator, heights, force, 1e-12)
    hardness = 1.2 * peak
    assert free.pressure.max() < hardness
    for on in (operator, fft_surface(128, pixel, E_STAR, np)):
        capped = contact_at_force(on, heights, force, 1e-12, hardness=hardness)
        assert capped.pressure.max() < hardness
        assert np.abs(capped.pressure - free.pressure).max() < 1e-6 * peak
        np.testing.assert_array_equal(capped.contact, free.contact)
        assert capped.delta == pytest.approx(free.delta, rel=1e-8)


@pytest.mark.parametrize("ratio", [100.0, 1000.0])
def test_far_above_first_yield_a_sphere_conducts_as_holms_plastic_spot(ratio) -> None:
    """F = ratio x F_c (F_c = pi^3 R^2 H^3 / (6 E*^2)): the mean pressure tends to H and the contact
    to a disc of radius sqrt(F / (pi H)); its punch resistance rho* / (2a) (measured within 0.07 %
    at 100 F_c, 0.3 % at 1000 F_c)."""
    n, radius, hardness = 128, 5e-3, 2e9
    force = ratio * yield_force(radius, E_STAR, hardness)
    holm = math.sqrt(force / (math.pi * hardness))
    pixel = holm / (0.3 * n)  # the spot's radius 38 pixels
    operator = fft_surface(n, pixel, E_STAR, np)
    state = contact_at_force(operator, surfaces.sphere(n, pixel, radius), force, 1e-10, hardness=hardness)
    assert state.force == pytest.approx(force, rel=1e-12)
    assert state.gap_spread < 1e-6 * holm**2 / radius  # the gap is closed below the cap
    resistance = 1.0 / punch_conductance(operator, state.contact, RHO).conductance
    assert resistance == pytest.approx(RHO / (2.0 * holm), rel=0.01)


def test_the_projection_keeps_the_mean_and_is_one_shift_clipped() -> None:
    rng = np.random.default_rng(5)
    trial = rng.normal(0.0, 2.0, (40, 40))
    for mean in (0.05, 0.5, 0.95):
        p = project_onto_box(trial, mean, 1.0, np)
        assert p.mean() == pytest.approx(mean, rel=MEAN_TOLERANCE)
        assert p.min() >= 0.0 and p.max() <= 1.0
        inside = (p > 0) & (p < 1)
        shift = (p - trial)[inside]
        assert np.ptp(shift) < 1e-12  # clip(trial + c, 0, H): the Euclidean projection
        np.testing.assert_allclose(p, np.clip(trial + shift.mean(), 0.0, 1.0), rtol=0, atol=1e-12)
    assert np.isnan(project_onto_box(np.full((4, 4), np.nan), 0.5, 1.0, np)).all()  # returns, does not loop


def test_the_error_vanishes_at_the_solution_and_the_solver_stops_at_its_limit() -> None:
    heights, pixel = _rough_sphere()
    n = heights.shape[0]
    operator = fft_surface(n, pixel, E_STAR, np)
    mean = 300.0 / (n * pixel) ** 2
    converged = solve_capped_at_mean_pressure(operator, heights, mean, 1e10, 1e-12)
    assert converged.error <= 1e-12 and converged.pressure.mean() == pytest.approx(mean, rel=1e-13)
    again = solve_capped_at_mean_pressure(operator, heights, mean, 1e10, 1e-12, start=converged.pressure)
    assert again.iterations == 0
    stopped = solve_capped_at_mean_pressure(operator, heights, mean, 1e10, 1e-12, max_iterations=2)
    assert stopped.iterations == 2 and stopped.error > 1e-6


def test_the_cap_refuses_what_it_cannot_solve() -> None:
    heights, pixel, force, peak = _hertz_sphere()
    with pytest.raises(ValueError, match="runs on g2tom's solver"):
        elastic.solve_pressure(elastic.free_surface(64, pixel, E_STAR), heights, force, 1e-8, hardness=peak)
    too_soft = 0.5 * force / (64 * pixel) ** 2  # the whole grid at H carries half the force
    with pytest.raises(ValueError, match="cannot carry the force"):
        contact_at_force(fft_surface(64, pixel, E_STAR, np), heights, force, hardness=too_soft)


def test_barber_after_plastic_loading_ties_the_conductance_to_the_unloading_stiffness() -> None:
    """The flattened heights carry the capped pressure elastically, and their elastic stiffness, not
    the capped loading slope dF/d(-delta), is K_punch = kappa E* rho*."""
    heights, pixel = _rough_sphere()
    operator = fft_surface(heights.shape[0], pixel, E_STAR, np)
    force, hardness = 300.0, 1e10  # 364 of 406 contact pixels at H
    state = contact_at_force(operator, heights, force, 1e-10, hardness=hardness)
    again = contact_at_force(operator, flattened_heights(operator, heights, state, hardness), force, 1e-10)
    assert np.abs(again.pressure - state.pressure).max() < 1e-6 * hardness
    assert again.delta == pytest.approx(state.delta, rel=1e-8)
    kappa = punch_conductance(operator, state.contact, RHO).conductance
    unloading = cases.barber_stiffness(operator, heights, state, force, hardness)
    assert kappa == pytest.approx(unloading / (E_STAR * RHO), rel=0.01)  # measured 0.09 %
    low, high = (contact_at_force(operator, heights, force * (1.0 + s * cases.BARBER_STEP), 1e-10, hardness=hardness)
                 for s in (-1, 1))
    loading = -(high.force - low.force) / (high.delta - low.delta)
    assert kappa > 1.5 * loading / (E_STAR * RHO)  # measured 1.78: the loading slope is not Barber's


def _hard(tmp_path) -> str:
    """A validated scenario: the paper's with material.hardness 2 GPa (a TOML file)."""
    path = tmp_path / "hard.toml"
    path.write_text('base = "paper"\n[material]\nhardness = 2e9\n')
    return str(path)


def test_validate_takes_the_validated_scenarios_hardness(tmp_path) -> None:
    hard = _hard(tmp_path)
    assert scene.with_hardness_of(scene.QUICK, hard).hardness == 2e9
    assert scene.with_hardness_of(scene.QUICK, "paper").hardness is None
    with pytest.raises(ConfigError, match="runs on g2tom's solver only"):
        scene.with_hardness_of(dataclasses.replace(scene.QUICK, solver="tamaas"), hard)
    assert "capped at H = 2e+09 Pa" in validate.plan_lines(scene.QUICK, hard)[0]
    assert "capped" not in validate.plan_lines(scene.QUICK, "paper")[0]


def test_a_capped_validation_case_holds_holms_area_and_barbers_theorem(tmp_path) -> None:
    """The quick set's convergence case at F' 4.85 capped at 2 GPa: the caps flattened to a mean
    pressure near H, Barber's ratio on the unloading stiffness near 1 (measured 1.00007); the
    hardness is in the case's key."""
    vset = dataclasses.replace(scene.QUICK, hardness=2e9)
    source = FieldSource.of(scene.g2tom_scenario(vset, vset.models[0], vset.discretizations[0]))
    case = cases.Case(0, 1, 128, False)
    force = 4.85 * vset.force_scale
    record = cases.run_case(vset, case, force, source, "k", tmp_path / "case.json")
    assert record["force"] == pytest.approx(force, rel=1e-9)
    assert record["contact_area"] == pytest.approx(force / 2e9, rel=0.02)  # measured 0.7 %
    assert record["barber_ratio"] == pytest.approx(1.0, abs=0.01)
    keys = {cases.case_key(v, case, force, source) for v in (vset, scene.QUICK)}
    assert len(keys) == 2


@pytest.mark.gpu
@gpu
def test_gpu_capped_solve_equals_numpy() -> None:
    import cupy

    heights, pixel, force, hardness = _cases()[1]
    n = heights.shape[0]
    on_gpu = contact_at_force(fft_surface(n, pixel, E_STAR, cupy), heights, force, 1e-12, hardness=hardness)
    on_cpu = contact_at_force(fft_surface(n, pixel, E_STAR, np), heights, force, 1e-12, hardness=hardness)
    np.testing.assert_array_equal(on_gpu.contact, on_cpu.contact)
    assert np.abs(on_gpu.pressure - on_cpu.pressure).max() < 1e-8 * hardness
    assert on_gpu.delta == pytest.approx(on_cpu.delta, rel=1e-8)


def test_a_lone_pixel_at_the_cap_steps_by_steepest_descent() -> None:
    """Three isolated pixels that can touch, one pixel's worth of force at H: an iterate puts one pixel
    alone at H and the rest at 0, where a conjugate step on the free set has no direction (0/0, the
    solve's pressure then not finite); the solver takes the steepest-descent step instead and converges."""
    n, pixel, e_star, hardness = 16, 1e-6, 1e11, 1e9
    operator = fft_surface(n, pixel, e_star, np)
    heights = np.full((n, n), -1e-3)
    for (i, j), z in zip([(0, 2), (12, 5), (10, 15)], [-2.5893606125679533e-08, -2.6439215182130694e-08,
                                                       -1.5321195166309355e-08]):
        heights[i, j] = z
    mean = hardness / n**2 * (1 - 1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = solve_capped_at_mean_pressure(operator, heights, mean, hardness, 1e-10, 300)
    assert result.error <= 1e-10 and np.all(np.isfinite(result.pressure))
    assert np.all((result.pressure >= 0) & (result.pressure <= hardness))
    assert result.pressure.sum() == pytest.approx(mean * n * n, rel=1e-13)
    assert result.pressure[10, 15] == result.pressure.max()  # the highest pixel carries most


class _IsolatedCap(CappedCap):
    """The capped law whose discs do not share their overlaps."""

    shares_overlap = False


def test_flattened_caps_that_share_their_discs_conduct_as_the_capped_full_field() -> None:
    """psi 50 (the GW set at H = 1.33 GPa), F' 8.63: most caps' discs overlap a neighbour's. The discrete
    caps that share their overlaps give the capped full field's clean R on the same surface within 3 %
    (the full field on 256^2; 0.8 % on 1024^2 in the validation), the caps counted apart 20 % too high."""
    from g2tom.physics import discrete_contact as dc
    from g2tom.physics.discrete_resistance import resistances
    from g2tom.reference import window

    hardness = 1.3323e9
    vset = dataclasses.replace(scene.QUICK, hardness=hardness)
    force = 8.63 * vset.force_scale
    side, _ = window.fitted_side(vset, 0, force)
    operator, _, state, _ = window.solve_in_window(vset, 0, 256, force, side)
    full_field = 1.0 / punch_conductance(operator, state.contact, vset.rho).conductance
    tips = surfaces.gw_asperities(vset.side, vset.eta, vset.sigma, vset.beta, scene.surface_stream(vset, 0))
    caps = dc.Asperities(tips.x, tips.y, tips.z)
    floor = dc.coupling_floor(vset.beta, vset.sigma)
    beta = dc.cap_radius("sphere", vset.beta, radius=vset.radius)
    gap = functools.partial(dc.cap_gap, shape="sphere", beta=vset.beta, radius=vset.radius)
    kernel = dc.interaction_kernel(tips.x, tips.y, floor)
    ratio = {}
    for name, law in (("shared", CappedCap(vset.e_star, beta, hardness)),
                      ("isolated", _IsolatedCap(vset.e_star, beta, hardness))):
        sol = dc.solve_forces(caps, gap, np.array([force]), vset.e_star, beta, floor, cap=law)
        ratio[name] = resistances(kernel, sol.radii, vset.rho)[0] / full_field
    assert ratio["shared"] == pytest.approx(1.0, abs=0.03)
    assert ratio["isolated"] > 1.15
