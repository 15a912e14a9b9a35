"""The point-interaction model: closed cases, the dense reference, the Rayleigh bound, films, the stage."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g2tom.cli import main as cli
from g2tom.compute import ComputeOptions
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.physics import constriction, point_model, point_solve
from g2tom.physics.crops import choose_crops
from g2tom.physics.interaction_folded import (
    interaction_apply,
    interaction_apply_columns,
    interaction_apply_dense,
    interaction_folded,
)
from g2tom.physics.spot_geometry import SpotGeometry
from tests.test_cube_stage import N, N_REAL, _build, _contact, _oxide

RHO = 7.2e-7  # ohm m
PITCH = 7.07e-5  # m
OPTIONS = ComputeOptions(progress=False)


def _whole(radius: np.ndarray) -> SpotGeometry:
    """Spots of radius ``radius`` (also their weights) on the whole window."""
    return SpotGeometry.whole_window(radius, radius, PITCH)


def _random_case(seed: int, n: int = 9, n_delta: int = 3, batch: int = 6):
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.0, 0.3 * PITCH, (n_delta, n, n)) * (rng.random((n_delta, n, n)) > 0.3)
    masks = rng.random((batch, n, n)) > rng.uniform(0.1, 0.9)
    return masks, radius


@pytest.mark.parametrize("n", [1, 2, 5, 8, 13])
def test_apply_matches_dense_matrix_and_contraction(n):
    u = np.random.default_rng(n).random((4, n, n))
    applied = interaction_apply(u, PITCH)
    np.testing.assert_allclose(applied, interaction_apply_dense(u, PITCH), rtol=1e-13, atol=1e-13 * applied.max(initial=1))
    q = np.einsum("bij,bij->b", u, applied)
    np.testing.assert_allclose(q, interaction_folded(u, PITCH), rtol=1e-13, atol=1e-30)


@pytest.mark.parametrize("n", [1, 6, 13])
def test_apply_in_float32_stays_float32_and_close(n):
    u = np.random.default_rng(n).random((n, n, 5))
    double = interaction_apply_columns(u, PITCH)
    single = interaction_apply_columns(u.astype(np.float32), PITCH)
    assert single.dtype == np.float32
    np.testing.assert_allclose(single, double, rtol=1e-5, atol=1e-6 * double.max(initial=1))
    assert np.array_equal(interaction_apply_columns(u, PITCH), double)  # the float64 scratch is untouched


def test_one_spot_conducts_2a_over_rho():
    radius = np.zeros((1, 5, 5))
    radius[0, 1, 3] = 4e-6
    res = point_model.resistance(np.ones((1, 5, 5), bool), _whole(radius), RHO)
    assert res.resistance[0, 0] == pytest.approx(RHO / (2 * 4e-6), rel=1e-14)
    greenwood = point_model.greenwood_resistance(np.ones((1, 5, 5), bool), _whole(radius), RHO)
    assert greenwood.resistance[0, 0] == pytest.approx(RHO / (2 * 4e-6), rel=1e-14)


def test_two_spots_match_the_2x2_solve_by_hand():
    a1, a2, d = 5e-6, 2e-6, np.hypot(2, 1) * PITCH
    radius = np.zeros((1, 3, 3))
    radius[0, 0, 0], radius[0, 1, 2] = a1, a2
    m12 = 1.0 / (np.pi * d)
    m11, m22 = 1.0 / (2 * a1), 1.0 / (2 * a2)
    det = m11 * m22 - m12**2
    total = (m22 - m12 + m11 - m12) / det  # sum of M^-1 [1, 1]
    res = point_model.resistance(np.ones((1, 3, 3), bool), _whole(radius), RHO)
    assert res.resistance[0, 0] == pytest.approx(RHO / total, rel=1e-12)
    greenwood = constriction.resistance(np.ones((1, 3, 3), bool), _whole(radius), RHO)
    assert greenwood.resistance[0, 0] > res.resistance[0, 0] * (1 + 1e-6)  # strictly above for two spots


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("film", [np.inf, 0.0, 3e-11])
def test_matches_dense_cholesky_solve(seed, film):
    masks, radius = _random_case(seed)
    res = point_model.resistance(masks, _whole(radius), RHO, film_resistance=film)
    dense, greenwood = point_model.resistance_dense(masks, radius, PITCH, RHO, film)
    assert np.array_equal(np.isinf(res.resistance), np.isinf(dense))
    finite = np.isfinite(dense)
    assert np.max(np.abs(res.resistance[finite] / dense[finite] - 1), initial=0) <= 1e-10  # the solver tolerance
    assert np.all(res.error_estimate <= 1e-10) and res.n_breakdown == 0
    closed = point_model.greenwood_resistance(masks, _whole(radius), RHO, film_resistance=film)
    np.testing.assert_allclose(closed.resistance[finite], greenwood[finite], rtol=1e-12)
    by_residual = point_model.resistance(masks, _whole(radius), RHO, film_resistance=film,
                                         criterion="residual")
    assert np.all(by_residual.residual <= 1e-10)
    assert np.max(np.abs(by_residual.resistance[finite] / dense[finite] - 1), initial=0) <= 1e-12


def _cluster_case(seed: int, n: int = 21, batch: int = 8):
    """Dense clusters of large spots (strong interaction, the hardest solves) under random oxide."""
    rng = np.random.default_rng(seed)
    r = np.hypot(*np.meshgrid(np.arange(n) - n // 2, np.arange(n) - n // 2))
    radius = np.stack([0.45 * PITCH * np.clip(1 - (r / (0.5 * n * s)) ** 2, 0, None) ** 0.5 for s in (0.5, 0.8, 1.0)])
    masks = rng.random((batch, n, n)) > rng.uniform(0.05, 0.7, (batch, 1, 1))
    return masks, radius


@pytest.mark.parametrize("tolerance", [1e-6, 1e-8, 1e-10, 1e-12])
def test_error_criterion_keeps_its_promise(tolerance):
    """The measured relative error of R never exceeds the tolerance of the energy-norm rule."""
    masks, radius = _cluster_case(int(-np.log10(tolerance)))
    res = point_model.resistance(masks, _whole(radius), RHO, solver_tolerance=tolerance)
    dense, _ = point_model.resistance_dense(masks, radius, PITCH, RHO)
    finite = np.isfinite(dense)
    error = np.abs(res.resistance[finite] / dense[finite] - 1)
    assert error.max() <= tolerance and np.all(res.error_estimate <= tolerance)
    loose = point_model.resistance(masks, _whole(radius), RHO,
                                   solver_tolerance=tolerance, criterion="residual")
    assert res.iterations.sum() < loose.iterations.sum()  # the point of the error rule


def test_single_precision_rounds_match_double_precision(monkeypatch):
    masks, radius = _cluster_case(4)
    single = point_model.resistance(masks, _whole(radius), RHO, solver_tolerance=1e-12)
    monkeypatch.setattr(point_solve, "SINGLE_PRECISION_DIAGONAL", 0.0)  # every round in float64
    double = point_model.resistance(masks, _whole(radius), RHO, solver_tolerance=1e-12)
    finite = np.isfinite(double.resistance)
    assert np.max(np.abs(single.resistance[finite] / double.resistance[finite] - 1)) <= 2e-12


def test_dense_operator_gives_the_same_solution():
    masks, radius = _random_case(7)
    fast = point_model.resistance(masks, _whole(radius), RHO)
    dense = point_model.resistance(masks, _whole(radius), RHO, "gemm")
    np.testing.assert_allclose(fast.resistance, dense.resistance, rtol=1e-10)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 10), oxide=st.floats(0.0, 0.95))
def test_greenwood_never_below_the_point_resistance(seed, n, oxide):
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.0, 0.45 * PITCH, (2, n, n)) * (rng.random((2, n, n)) > 0.2)
    masks = rng.random((3, n, n)) >= oxide
    point = point_model.resistance(masks, _whole(radius), RHO).resistance
    greenwood = constriction.resistance(masks, _whole(radius), RHO).resistance
    assert np.array_equal(np.isinf(point), np.isinf(greenwood))
    finite = np.isfinite(point)
    assert np.all(greenwood[finite] >= point[finite] * (1 - 1e-12))


def test_film_limits_clean_and_insulating():
    masks, radius = _random_case(11)

    def r(mask, film):
        return point_model.resistance(mask, _whole(radius), RHO, film_resistance=film).resistance

    clean = r(np.ones_like(masks), np.inf)
    np.testing.assert_allclose(r(masks, 0.0), clean, rtol=1e-9)
    insulating = r(masks, np.inf)
    finite = np.isfinite(insulating)
    films = [1e-12, 1e-10, 1e-8, 1e-4]
    values = [r(masks, f) for f in films]
    for low, high in zip(values, values[1:]):
        assert np.all(high >= low * (1 - 1e-10))  # R grows with the film's resistance
    assert np.all(values[0] >= clean * (1 - 1e-10)) and np.all(values[-1][finite] <= insulating[finite] * (1 + 1e-10))
    assert np.max(np.abs(values[-1][finite] / insulating[finite] - 1)) <= 1e-5
    assert np.all(values[-1][~finite] > 1e3 * clean[~finite])  # the open circuits become huge, finite


def test_greenwood_with_films_is_the_rayleigh_quotient_and_reduces_to_eq13():
    masks, radius = _random_case(5)
    plain = constriction.resistance(masks, _whole(radius), RHO)
    same = point_model.greenwood_resistance(masks, _whole(radius), RHO)
    np.testing.assert_allclose(same.resistance, plain.resistance, rtol=1e-12)
    np.testing.assert_allclose(same.resistance_self, plain.resistance_self, rtol=1e-12)
    film = point_model.greenwood_resistance(masks, _whole(radius), RHO, film_resistance=2e-11)
    exact = point_model.resistance(masks, _whole(radius), RHO, film_resistance=2e-11)
    _, dense_greenwood = point_model.resistance_dense(masks, radius, PITCH, RHO, 2e-11)
    np.testing.assert_allclose(film.resistance, dense_greenwood, rtol=1e-12)
    assert np.all(film.resistance >= exact.resistance * (1 - 1e-12))


def test_cropping_bound_holds():
    contact = _contact(n=15, n_delta=5)
    radius = contact["spot_radius"].values
    masks = np.random.default_rng(2).random((8, 15, 15)) > 0.4
    crops = choose_crops(radius, radius, PITCH, 1e-3)
    assert crops.min() < 15
    cropped = point_model.resistance(masks, SpotGeometry(radius, radius, PITCH, crops, 1e-3), RHO)
    whole = point_model.resistance(masks, _whole(radius), RHO)
    finite = np.isfinite(whole.resistance)
    error = np.abs(cropped.resistance[finite] / whole.resistance[finite] - 1)
    assert np.all(error <= cropped.crop_bound[finite] + 1e-9) and np.all(cropped.crop_bound <= 1e-3)
    assert np.all(cropped.resistance[finite] >= whole.resistance[finite] * (1 - 1e-9))  # cropping lowers kappa


def test_no_current_inside_the_crop_is_solved_on_the_whole_window():
    contact = _contact(n=15, n_delta=5)
    radius = contact["spot_radius"].values
    crops = choose_crops(radius, radius, PITCH, 1e-3)
    edge = (15 - crops.min()) // 2
    mask = np.zeros((1, 15, 15), bool)
    mask[0, :edge, :] = True  # current only outside the smallest crop
    res = point_model.resistance(mask, SpotGeometry(radius, radius, PITCH, crops, 1e-3), RHO)
    dense, _ = point_model.resistance_dense(mask, radius, PITCH, RHO)
    finite = np.isfinite(dense)
    assert finite[0, 0] and np.array_equal(finite, np.isfinite(res.resistance))
    assert np.max(np.abs(res.resistance[finite] / dense[finite] - 1)) <= 1e-10 and res.n_uncropped >= 1


def test_tiny_spots_neither_underflow_nor_stop_early():
    """Spots of 1e-30 m (edge cells of a light contact reach 1e-51 m) are solved like any other."""
    masks, radius = _random_case(9, n=11)
    radius = radius * 1e-30 / PITCH
    res = point_model.resistance(masks, _whole(radius), RHO)
    dense, _ = point_model.resistance_dense(masks, radius, PITCH, RHO)
    finite = np.isfinite(dense)
    assert np.array_equal(finite, np.isfinite(res.resistance))
    assert np.max(np.abs(res.resistance[finite] / dense[finite] - 1)) <= 1e-10
    assert np.all(res.error_estimate <= 1e-10)


def test_current_appearing_at_a_later_load_step_is_solved_to_the_tolerance():
    """No current at the first step (no spot yet), some at the second: the warm start is empty."""
    masks, radius = _cluster_case(6)
    radius = np.concatenate([np.zeros_like(radius[:1]), radius[1:]])
    res = point_model.resistance(masks, _whole(radius), RHO)
    dense, _ = point_model.resistance_dense(masks, radius, PITCH, RHO)
    finite = np.isfinite(dense)
    assert not finite[:, 0].any() and finite[:, 1].all()
    assert np.max(np.abs(res.resistance[finite] / dense[finite] - 1)) <= 1e-10


def test_iteration_cap_is_recorded_not_hidden():
    masks, radius = _random_case(3, n=11)
    res = point_model.resistance(masks, _whole(radius), RHO, max_iterations=1)
    assert np.all(res.iterations <= 1) and np.any(res.residual > 1e-10)


@pytest.mark.parametrize("kwargs", [{"solver_tolerance": 0.0}, {"max_iterations": 0}, {"film_resistance": -1.0},
                                    {"film_resistance": np.nan}, {"criterion": "energy"}])
def test_physics_rejects_bad_settings(kwargs):
    masks, radius = _random_case(0)
    with pytest.raises(ValueError):
        point_model.resistance(masks, _whole(radius), RHO, **kwargs)


@pytest.fixture(scope="module")
def inputs():
    return _contact(), _oxide()


def _scenario(**overrides):
    return load_scenario("paper_gt", {"oxide.ensemble": "fixed", "oxide.n_realizations": N_REAL, **overrides})


def test_stage_point_model_matches_dense_and_records_the_solver(inputs):
    ds = _build(_scenario(**{"cube.model": "point", "compute.cube_chunk": 3}), *inputs)
    assert ds.attrs["model"] == "point" and ds.attrs["n_not_converged"] == 0
    for name in ("iterations", "residual", "error_estimate"):
        assert ds[name].dims == ("xi", "lambda", "delta", "realization") and "units" in ds[name].attrs
    assert ds["iterations"].values.max() <= 30 and np.nanmax(ds["error_estimate"].values) <= 1e-10
    contact, oxide = inputs
    psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values
    thr = oxide["threshold"].transpose("xi", "lambda", "realization").values
    masks = psi[None, :, :2] < thr[:, :, :2, None, None]
    radius = contact["spot_radius"].values
    dense, _ = point_model.resistance_dense(masks.reshape(-1, N, N), radius, PITCH, RHO)
    got = ds["resistance"].values[:, :, :, :2].transpose(0, 1, 3, 2).reshape(dense.shape)
    finite = np.isfinite(dense)
    assert np.array_equal(finite, np.isfinite(got))
    assert np.max(np.abs(got[finite] / dense[finite] - 1)) <= 1e-6  # the crop tolerance
    greenwood = _build(_scenario(), *inputs)["resistance"].values
    assert np.all(greenwood[np.isfinite(greenwood)] >= ds["resistance"].values[np.isfinite(greenwood)] * (1 - 1e-6))


def test_stage_point_model_invariant_under_chunking_and_scheduler(inputs, cluster_address):
    base = _build(_scenario(**{"cube.model": "point", "compute.cube_chunk": 3}), *inputs)
    for chunk, workers, scheduler in ((1, 1, None), (N_REAL, None, None), (4, None, cluster_address)):
        options = ComputeOptions(progress=False, workers=workers, scheduler=scheduler)  # one thread, threads, local cluster
        other = _build(_scenario(**{"cube.model": "point", "compute.cube_chunk": chunk}), *inputs, options)
        for name in ("resistance", "iterations", "residual", "error_estimate", "n_conducting"):
            np.testing.assert_array_equal(other[name].values, base[name].values)


def test_stage_resistive_film_both_models(inputs):
    film = {"oxide.film": "resistive", "oxide.film_resistance": 1e-11}
    point = _build(_scenario(**film, **{"cube.model": "point"}), *inputs)
    greenwood = _build(_scenario(**film), *inputs)
    assert point.attrs["n_open_total"] == 0 and np.all(point["n_conducting"].values == N * N)
    assert np.all(greenwood["resistance"].values >= point["resistance"].values * (1 - 1e-9))
    insulating = _build(_scenario(**{"cube.model": "point"}), *inputs)["resistance"].values
    assert np.all(point["resistance"].values <= insulating * (1 + 1e-6))


@pytest.mark.parametrize(
    "override, message",
    [
        ("cube.solver_tolerance=0", "cube.solver_tolerance = 0"),
        ("cube.solver_tolerance=-1e-10", "cube.solver_tolerance"),
        ("cube.max_iterations=0", "cube.max_iterations = 0"),
        ("oxide.film_resistance=-1e-11", "oxide.film_resistance = -1e-11"),
        ("oxide.film_resistance=inf", "oxide.film_resistance = inf"),
        ("oxide.film_resistance=nan", "oxide.film_resistance = nan"),
        ("oxide.film=leaky", "oxide.film = 'leaky'"),
        ("cube.model=exact", "cube.model = 'exact'"),
        ("cube.solver_criterion=energy", "cube.solver_criterion = 'energy'"),
    ],
)
def test_bad_settings_are_config_errors(override, message):
    with pytest.raises(ConfigError, match=message.replace(".", r"\.").replace("(", r"\(")):
        load_scenario("paper_gt", [override])


def test_point_model_needs_radius_weights_and_an_applicable_operator():
    with pytest.raises(ConfigError, match="cube.weights = 'area'"):
        load_scenario("published", ["cube.model=point"])
    with pytest.raises(ConfigError, match="compute.interaction_sum = 'fft'"):
        load_scenario("paper_gt", ["cube.model=point", "compute.interaction_sum=fft"])


def test_cli_exits_2_on_bad_solver_settings(tmp_path, capsys):
    assert cli.main(["cube", "--set", "cube.max_iterations=0", "--data-dir", str(tmp_path), "--no-progress"]) == 2
    assert "cube.max_iterations = 0" in capsys.readouterr().err


def test_film_does_not_touch_the_oxide_stage_hash():
    insulating = load_scenario("paper_gt")
    resistive = load_scenario("paper_gt", {"oxide.film": "resistive"})
    assert resistive.config_hash("oxide") == insulating.config_hash("oxide")
    assert resistive.config_hash("cube") != insulating.config_hash("cube")
