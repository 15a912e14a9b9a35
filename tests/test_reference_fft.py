"""The reference's array-namespace path (Love's coefficients by FFT, our Polonsky-Keer, CG punch):
checked on NumPy against closed forms, direct sums and tamaas, and on a GPU against the CPU.

The ``gpu`` tests need CuPy and a device; elsewhere they skip, saying why. Everything they run on
CuPy runs here on NumPy through the same code.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import dblquad
from scipy.sparse.linalg import cg

from g2tom.physics.boussinesq import influence_coefficients, rectangle_integral
from g2tom.reference import cases, cost, devices, elastic, scene, surfaces
from g2tom.reference.contact import contact_at_force
from g2tom.reference.fft_surface import FftSurface, fft_surface
from g2tom.reference.polonsky_keer import solve_at_mean_pressure
from g2tom.reference.punch import conjugate_gradients, punch_conductance
from g2tom.scene import FieldSource

E_STAR, RHO = 1.154e11, 7.2e-7
GPU_MISSING = devices.gpu_missing()
gpu = pytest.mark.skipif(GPU_MISSING is not None, reason=f"no GPU to test on: {GPU_MISSING}")


def _rough_sphere(n: int = 128, seed: int = 3) -> tuple[np.ndarray, float]:
    """A GW surface on a 2 mm sphere, 8 pixels per asperity spacing; heights (m) and pixel (m)."""
    sigma, eta, beta = 20e-6, 2e8, 60e-6
    pixel = 1.0 / math.sqrt(eta) / 8.0
    asperities = surfaces.gw_asperities(n * pixel, eta, sigma, beta, np.random.default_rng(seed))
    return surfaces.gw_heights(asperities, n, pixel, -8 * sigma) + surfaces.sphere(n, pixel, 2e-3), pixel


@pytest.mark.parametrize("x, y", [(1.0, 0.0), (2.0, 3.0), (-5.0, 1.0)])
def test_love_integral_equals_quadrature_of_one_over_r(x, y) -> None:
    half_x, half_y = 0.5, 0.7  # a rectangle, off the point
    numeric, _ = dblquad(lambda v, u: 1.0 / math.hypot(u, v), x - half_x, x + half_x, y - half_y, y + half_y,
                         epsabs=1e-13, epsrel=1e-12)
    assert float(rectangle_integral(x, y, half_x, half_y)) == pytest.approx(numeric, rel=1e-10)


def test_own_pixel_coefficient_is_the_square_closed_form() -> None:
    """Centre of a square of side h: integral of 1/r = 4 h ln(1 + sqrt 2)."""
    h = 3e-6
    own = influence_coefficients(4, h, E_STAR)[0, 0]
    assert own == pytest.approx(4.0 * h * math.log(1.0 + math.sqrt(2.0)) / (math.pi * E_STAR), rel=1e-14)


def test_fft_operator_is_the_direct_sum_and_tamaas() -> None:
    n, pixel = 24, 2e-6
    pressure = np.random.default_rng(0).random((n, n)) * 1e8
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    direct = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            direct[a, b] = np.sum(pressure * rectangle_integral((j - b) * pixel, (i - a) * pixel, pixel / 2, pixel / 2))
    direct /= math.pi * E_STAR
    own = fft_surface(n, pixel, E_STAR, np)(pressure)
    np.testing.assert_allclose(own, direct, rtol=1e-12)
    np.testing.assert_allclose(own, elastic.free_surface(n, pixel, E_STAR)(pressure), rtol=1e-11)


def test_fft_operator_refuses_a_bad_grid() -> None:
    with pytest.raises(ValueError, match="pixel = -1"):
        fft_surface(8, -1.0, E_STAR, np)


def test_our_polonsky_keer_on_a_smooth_sphere_gives_hertz() -> None:
    n, side, radius = 128, 1e-3, 5e-3
    pixel = side / n
    a = 0.3 * side
    force = 4.0 * E_STAR * a**3 / (3.0 * radius)
    state = contact_at_force(fft_surface(n, pixel, E_STAR, np), surfaces.sphere(n, pixel, radius), force)
    assert state.force == pytest.approx(force, rel=1e-12)
    assert state.gap_spread < 1e-6 * a**2 / radius
    assert np.sqrt(state.contact.sum() * pixel**2 / np.pi) == pytest.approx(a, rel=0.01)
    assert state.delta == pytest.approx(-(a**2) / radius, rel=0.01)


@pytest.mark.parametrize("force", [3.0, 30.0, 300.0])  # 5, 21 and 129 contact pixels
def test_our_polonsky_keer_equals_tamaas_on_a_rough_sphere(force) -> None:
    heights, pixel = _rough_sphere()
    n = heights.shape[0]
    ours = contact_at_force(fft_surface(n, pixel, E_STAR, np), heights, force)
    theirs = contact_at_force(elastic.free_surface(n, pixel, E_STAR), heights, force)
    np.testing.assert_array_equal(ours.contact, theirs.contact)
    assert ours.force == pytest.approx(theirs.force, rel=1e-12)
    assert ours.delta == pytest.approx(theirs.delta, rel=1e-8)
    assert np.abs(ours.pressure - theirs.pressure).max() < 1e-6 * theirs.pressure.max()
    assert ours.gap_spread < 1e-7 * 20e-6  # closed on the contact set to 1e-7 sigma


def test_our_solver_reports_its_error_and_stops_at_the_limit() -> None:
    heights, pixel = _rough_sphere()
    operator = fft_surface(heights.shape[0], pixel, E_STAR, np)
    result = solve_at_mean_pressure(operator, heights, 300.0 / (heights.shape[0] * pixel) ** 2, 1e-12,
                                    max_iterations=3)
    assert result.iterations == 3 and result.error > 1e-12
    converged = solve_at_mean_pressure(operator, heights, 300.0 / (heights.shape[0] * pixel) ** 2, 1e-12)
    assert converged.error <= 1e-12 < result.error
    assert np.all(converged.pressure >= 0.0)


def test_a_start_near_the_solution_converges_sooner_to_the_same_pressure() -> None:
    """As tamaas' model keeps its traction, an operator's next solve starts from its last (Barber's nearby loads)."""
    heights, pixel = _rough_sphere()
    n = heights.shape[0]
    operator = fft_surface(n, pixel, E_STAR, np)
    mean = 300.0 / (n * pixel) ** 2
    near = solve_at_mean_pressure(operator, heights, mean, 1e-11)
    warm = solve_at_mean_pressure(operator, heights, 1.01 * mean, 1e-11, start=near.pressure)
    cold = solve_at_mean_pressure(operator, heights, 1.01 * mean, 1e-11)
    assert warm.iterations < cold.iterations
    np.testing.assert_allclose(warm.pressure, cold.pressure, rtol=0, atol=1e-7 * cold.pressure.max())
    assert warm.pressure.mean() == pytest.approx(1.01 * mean, rel=1e-12)
    first = elastic.solve_pressure(operator, heights, 300.0, 1e-10)  # the operator remembers it
    np.testing.assert_array_equal(operator.last_pressure, first)


def test_solver_failure_names_the_error(monkeypatch) -> None:
    heights, pixel = _rough_sphere()
    monkeypatch.setattr(elastic, "MAX_ITERATIONS", 2)
    with pytest.raises(elastic.SolverFailure, match=r"after 2 iterations"):
        elastic.solve_pressure(fft_surface(heights.shape[0], pixel, E_STAR, np), heights, 300.0, 1e-8)


def test_conjugate_gradients_solves_a_symmetric_positive_definite_system() -> None:
    rng = np.random.default_rng(2)
    m = rng.standard_normal((40, 40))
    matrix = m @ m.T + 40.0 * np.eye(40)
    b = rng.standard_normal(40)
    x, iterations = conjugate_gradients(lambda v: matrix @ v, b, 1e-12, 200, np)
    np.testing.assert_allclose(x, np.linalg.solve(matrix, b), rtol=1e-9)
    assert 0 < iterations <= 40 + 5
    scipy_x, info = cg(matrix, b, rtol=1e-12, atol=0.0)
    assert info == 0 and np.allclose(x, scipy_x, rtol=1e-9)
    with pytest.raises(RuntimeError, match="did not converge"):
        conjugate_gradients(lambda v: matrix @ v, b, 1e-14, 2, np)


@pytest.mark.parametrize("force", [3.0, 300.0])
def test_punch_on_our_operator_equals_tamaas(force) -> None:
    heights, pixel = _rough_sphere()
    n = heights.shape[0]
    tamaas_operator = elastic.free_surface(n, pixel, E_STAR)
    contact = contact_at_force(tamaas_operator, heights, force).contact
    ours = punch_conductance(fft_surface(n, pixel, E_STAR, np), contact, RHO)
    theirs = punch_conductance(tamaas_operator, contact, RHO)
    assert ours.conductance == pytest.approx(theirs.conductance, rel=1e-6)
    assert punch_conductance(fft_surface(n, pixel, E_STAR, np), np.zeros((n, n), bool), RHO).conductance == 0.0


def test_device_choice(monkeypatch) -> None:
    assert devices.resolve("cpu") == "cpu"
    assert devices.namespace("cpu") is np
    with pytest.raises(ValueError, match=r"--device 'tpu' is not allowed: must be one of cpu, gpu, auto"):
        devices.resolve("tpu")
    monkeypatch.setattr(devices, "gpu_missing", lambda: "CuPy sees no GPU (0 devices)")
    assert devices.resolve("auto") == "cpu"
    with pytest.raises(ValueError, match=r"--device gpu cannot be used: CuPy sees no GPU"):
        devices.resolve("gpu")
    monkeypatch.setattr(devices, "gpu_missing", lambda: None)
    assert devices.resolve("auto") == devices.resolve("gpu") == "gpu"


def test_solver_choice() -> None:
    assert devices.solver_for(None, "cpu") == devices.solver_for(None, "gpu") == "g2tom"
    assert devices.solver_for("g2tom", "cpu") == "g2tom"
    with pytest.raises(ValueError, match=r"--solver 'fenics' is not allowed: must be one of tamaas, g2tom"):
        devices.solver_for("fenics", "cpu")
    with pytest.raises(ValueError, match=r"--solver tamaas is not allowed with --device gpu"):
        devices.solver_for("tamaas", "gpu")
    assert isinstance(elastic.free_surface(8, 1e-6, E_STAR, "cpu", "g2tom"), FftSurface)
    assert isinstance(elastic.free_surface(8, 1e-6, E_STAR), elastic.FreeSurface)


def test_the_device_and_solver_shape_no_case_key() -> None:
    source = FieldSource.of(scene.g2tom_scenario(scene.QUICK, scene.QUICK.models[0], scene.QUICK.discretizations[0]))
    case = cases.plan_cases(scene.QUICK)[0]
    keys = {cases.case_key(dataclasses.replace(scene.QUICK, device=d, solver=s), case, 1.0, source)
            for d, s in (("cpu", "tamaas"), ("cpu", "g2tom"), ("gpu", "g2tom"))}
    assert len(keys) == 1


def _one_case_on(settings: list[tuple[str, str]], tmp_path) -> list[dict]:
    """One whole validation case (probe, fitted window, contact, clean and oxidized punches) of the
    quick set at F' 4.85, on each (device, solver)."""
    vset = scene.QUICK
    source = FieldSource.of(scene.g2tom_scenario(vset, vset.models[0], vset.discretizations[0]))
    case = next(c for c in cases.plan_cases(vset) if c.oxide)
    return [cases.run_case(dataclasses.replace(vset, device=d, solver=s), case, 4.85 * vset.force_scale, source, "k",
                           tmp_path / f"{d}-{s}.json") for d, s in settings]


def _assert_same_case(ours: dict, theirs: dict) -> None:
    for name in ("force", "delta", "contact_area", "side", "resistance_clean"):
        assert ours[name] == pytest.approx(theirs[name], rel=1e-6), name
    np.testing.assert_allclose(ours["resistance"], theirs["resistance"], rtol=1e-6)


def test_our_solver_case_equals_the_tamaas_case(tmp_path) -> None:
    ours, theirs = _one_case_on([("cpu", "g2tom"), ("cpu", "tamaas")], tmp_path)
    assert (ours["solver"], theirs["solver"]) == ("g2tom", "tamaas")
    _assert_same_case(ours, theirs)


# --- on a GPU: the same code on CuPy against NumPy and tamaas -------------------------------------------------


@pytest.mark.gpu
@gpu
def test_gpu_operator_equals_numpy() -> None:
    import cupy

    n, pixel = 256, 2e-6
    pressure = np.random.default_rng(0).random((n, n)) * 1e8
    on_gpu = fft_surface(n, pixel, E_STAR, cupy)(pressure)
    np.testing.assert_allclose(on_gpu, fft_surface(n, pixel, E_STAR, np)(pressure), rtol=1e-12, atol=0)


@pytest.mark.gpu
@gpu
@pytest.mark.parametrize("force", [3.0, 30.0, 300.0])
def test_gpu_contact_and_punch_equal_tamaas(force) -> None:
    heights, pixel = _rough_sphere(256)
    n = heights.shape[0]
    gpu_operator = elastic.free_surface(n, pixel, E_STAR, "gpu")
    ours = contact_at_force(gpu_operator, heights, force)
    cpu_operator = elastic.free_surface(n, pixel, E_STAR)
    theirs = contact_at_force(cpu_operator, heights, force)
    np.testing.assert_array_equal(ours.contact, theirs.contact)
    assert ours.force == pytest.approx(theirs.force, rel=1e-8)
    assert ours.delta == pytest.approx(theirs.delta, rel=1e-8)
    assert (punch_conductance(gpu_operator, theirs.contact, RHO).conductance
            == pytest.approx(punch_conductance(cpu_operator, theirs.contact, RHO).conductance, rel=1e-6))


@pytest.mark.gpu
@gpu
def test_gpu_case_equals_the_cpu_case(tmp_path) -> None:
    on_gpu, on_cpu = _one_case_on([("gpu", "g2tom"), ("cpu", "tamaas")], tmp_path)
    assert on_gpu["device"] == "gpu" and on_cpu["device"] == "cpu"
    _assert_same_case(on_gpu, on_cpu)


@pytest.mark.parametrize("grid, ensemble, oxide, load, measured", [
    (256, True, True, 0.0752, 0.29), (1024, False, True, 4.85, 0.47), (512, False, False, 4.85, 0.60)])
def test_the_plan_of_a_gpu_case_is_within_one_and_a_half_of_the_h200s(grid, ensemble, oxide, load, measured) -> None:
    """The medians of the default GW validation on an H200 (2026-11-27) by kind of case."""
    vset = dataclasses.replace(scene.DEFAULT, device="gpu", solver="g2tom")
    case = cases.Case(0, 0, grid, oxide, ensemble=ensemble)
    assert 1 / 1.5 < cost.case_seconds(vset, case, load) / measured < 1.5


def test_the_plan_of_our_solver_on_the_cpu_is_tamaas_over_the_measured_speedup() -> None:
    case = cases.plan_cases(scene.DEFAULT)[0]
    tamaas = cost.case_seconds(dataclasses.replace(scene.DEFAULT, solver="tamaas"), case, 4.85)
    ours = cost.case_seconds(scene.DEFAULT, case, 4.85)
    assert ours == pytest.approx(tamaas / cost.G2TOM_CPU_SPEEDUP, rel=1e-12)


def test_the_reference_benchmarks_compare_our_solver_with_tamaas_and_say_when_there_is_no_gpu(monkeypatch) -> None:
    from g2tom.bench import gpu as gpu_bench
    from g2tom.bench.reference_step import largest_differences, row

    result = row(96, ("cpu", "g2tom", "g2tom"), ("cpu", "tamaas", "tamaas"), 1, 1, warm=False)
    assert result["contact_pixels"] > 0 and result["contact_pixels_differing"] == 0
    assert result["delta_difference"] < 1e-7 and result["conductance_difference"] < 1e-6
    assert result["contact_ratio"] == result["tamaas_contact_seconds"] / result["g2tom_contact_seconds"]
    assert largest_differences([result, {"n": 1}])["delta_difference"] == result["delta_difference"]
    assert largest_differences([{"n": 1}]) == {}
    monkeypatch.setattr(devices, "gpu_missing", lambda: "CuPy sees no GPU (0 devices)")
    assert gpu_bench.run(None) == {"skipped": "no GPU: CuPy sees no GPU (0 devices)"}
