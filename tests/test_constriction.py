"""Greenwood's multi-spot resistance: the double sum, the fast exact paths (interaction, interaction_fft)
and cropping (crops)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g2tom.physics import constriction as cn
from g2tom.physics import crops as cc
from g2tom.physics import interaction as ia
from g2tom.physics import interaction_fft as fi
from g2tom.physics.spot_geometry import SpotGeometry

RHO = 7.2e-7  # ohm m
PITCH = 7.0e-5  # m
FAST = ("gemm", "fft", "dft_gemm", "folded")


def _gaussian_spots(n: int, widths: tuple[float, ...], peak: float = 2e-6) -> np.ndarray:
    """Radii (m) of a centred Gaussian-like profile per load step, shape (len(widths), n, n)."""
    c = np.arange(n) - (n - 1) / 2.0
    r2 = c[:, None] ** 2 + c[None, :] ** 2
    return np.stack([peak * np.exp(-r2 / (2.0 * s**2)) for s in widths])


def _weights(radius: np.ndarray, kind: str) -> np.ndarray:
    return radius if kind == "radius" else np.pi * radius**2



def _rel(a: np.ndarray, b: np.ndarray) -> float:
    finite = np.isfinite(b)
    assert np.array_equal(finite, np.isfinite(a))
    return float(np.max(np.abs(a[finite] / b[finite] - 1.0), initial=0.0))


random_maps = st.tuples(
    st.integers(1, 9),  # n
    st.integers(1, 5),  # batch
    st.floats(0.0, 1.0),  # conducting probability
    st.integers(0, 2**32 - 1),  # seed
)


@settings(max_examples=40, deadline=None)
@given(random_maps, st.floats(1e-6, 1e-3))
def test_fast_paths_equal_double_sum(case, pitch):
    n, batch, p, seed = case
    rng = np.random.default_rng(seed)
    u = rng.lognormal(-12.0, 2.0, (batch, n, n)) * (rng.random((batch, n, n)) < p)
    reference = ia.interaction_direct(u, pitch)
    scale = np.sum(u, axis=(1, 2)) ** 2 / pitch  # |Q| <= scale
    for method in FAST:
        q = ia.interaction_sum(u, pitch, method)
        assert np.all(np.abs(q - reference) <= 1e-13 * scale), method


@settings(max_examples=25, deadline=None)
@given(random_maps, st.sampled_from(["radius", "area"]))
def test_resistance_fast_equals_direct(case, kind):
    n, batch, p, seed = case
    rng = np.random.default_rng(seed)
    radius = rng.random((3, n, n)) * 1e-6 * (rng.random((3, n, n)) < 0.9)
    masks = rng.random((batch, n, n)) < p
    weights = _weights(radius, kind)
    ref = cn.resistance(masks, SpotGeometry.whole_window(radius, weights, PITCH), RHO, "direct")
    for method in FAST + ("auto",):
        got = cn.resistance(masks, SpotGeometry.whole_window(radius, weights, PITCH), RHO, method)
        assert _rel(got.resistance, ref.resistance) <= 1e-12
        assert _rel(got.resistance_interaction + got.resistance_self, ref.resistance) <= 1e-12
        np.testing.assert_array_equal(got.n_conducting, ref.n_conducting)


def test_single_spot_is_rho_over_2a():
    radius = np.zeros((1, 5, 5))
    radius[0, 1, 3] = 3e-6
    for method in FAST + ("direct",):
        res = cn.resistance(np.ones((1, 5, 5), bool), SpotGeometry(radius, radius, PITCH, [5], 0.0), RHO, method)
        assert res.resistance[0, 0] == pytest.approx(RHO / (2 * 3e-6), rel=1e-15)
        assert res.resistance_interaction[0, 0] == 0.0
        assert res.n_conducting[0, 0] == 1


@pytest.mark.parametrize("kind", ["radius", "area"])
def test_two_spots_by_hand(kind):
    a1, a2 = 2e-6, 5e-6
    radius = np.zeros((1, 6, 6))
    radius[0, 0, 1], radius[0, 4, 4] = a1, a2
    w1, w2 = (a1, a2) if kind == "radius" else (math.pi * a1**2, math.pi * a2**2)
    d = PITCH * math.hypot(4, 3)
    expected = RHO / (2 * (a1 + a2)) + RHO * 2 * w1 * w2 / d / (math.pi * (w1 + w2) ** 2)
    spots = SpotGeometry(radius, _weights(radius, kind), PITCH, [6], 0.0)
    for method in FAST + ("direct",):
        res = cn.resistance(np.ones((1, 6, 6), bool), spots, RHO, method)
        assert res.resistance[0, 0] == pytest.approx(expected, rel=1e-14)


def test_all_oxidized_is_open_circuit():
    radius = _gaussian_spots(7, (1.0, 3.0))
    res = cn.resistance(np.zeros((2, 7, 7), bool), SpotGeometry(radius, radius, PITCH, [7, 7], 1e-6), RHO)
    for term in (res.resistance, res.resistance_self, res.resistance_interaction):
        assert np.all(np.isposinf(term))
    assert np.all(res.n_conducting == 0)


def test_spot_permutation_and_grid_symmetries():
    rng = np.random.default_rng(3)
    x, y, w = rng.random(30), rng.random(30), rng.random(30)
    perm = rng.permutation(30)
    assert ia.pair_sum_points(x[perm], y[perm], w[perm]) == pytest.approx(ia.pair_sum_points(x, y, w), rel=1e-14)
    u = rng.random((1, 9, 9)) * (rng.random((1, 9, 9)) < 0.5)
    iy, ix = np.nonzero(u[0])
    points = ia.pair_sum_points(ix * PITCH, iy * PITCH, u[0, iy, ix])
    for image in (u, u[:, ::-1], u[:, :, ::-1], u.transpose(0, 2, 1)):
        for method in FAST:
            assert ia.interaction_sum(np.ascontiguousarray(image), PITCH, method)[0] == pytest.approx(points, rel=1e-13)


def test_resistance_scales_with_rho():
    rng = np.random.default_rng(4)
    radius = _gaussian_spots(9, (1.5, 3.0))
    masks = rng.random((5, 9, 9)) < 0.5
    one = cn.resistance(masks, SpotGeometry(radius, radius, PITCH, [9, 9], 0.0), 1.0)
    scaled = cn.resistance(masks, SpotGeometry(radius, radius, PITCH, [9, 9], 0.0), 3.5)
    np.testing.assert_allclose(scaled.resistance, 3.5 * one.resistance, rtol=1e-15)


@pytest.mark.parametrize(("kind", "p"), [("radius", 0.4), ("area", 0.05)])
def test_results_bit_identical_whatever_the_batch(kind, p):
    """Also for the entries recomputed uncropped (sparse masks with area weights)."""
    rng = np.random.default_rng(5)
    radius = _gaussian_spots(13, (1.0, 2.0, 4.0))
    weights = _weights(radius, kind)
    masks = rng.random((300, 13, 13)) < p
    crops = cc.choose_crops(radius, weights, PITCH, 1e-6)
    spots = SpotGeometry(radius, weights, PITCH, crops, 1e-6)
    full = cn.resistance(masks, spots, RHO)
    assert (full.n_uncropped > 0) == (kind == "area")
    whole = full.resistance
    pieces = [cn.resistance(masks[i : i + 7], spots, RHO).resistance for i in range(0, 300, 7)]
    np.testing.assert_array_equal(np.concatenate(pieces), whole)
    perm = rng.permutation(300)
    np.testing.assert_array_equal(cn.resistance(masks[perm], spots, RHO).resistance, whole[perm])


@settings(max_examples=20, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sampled_from(["radius", "area"]),
    st.sampled_from([1e-2, 1e-4, 1e-6]),
    st.floats(0.05, 1.0),
    st.sampled_from([14, 15]),
)
def test_crop_error_within_tolerance_and_bound(seed, kind, tolerance, p, n):
    rng = np.random.default_rng(seed)
    radius = _gaussian_spots(n, tuple(rng.uniform(0.7, 4.0, 3))) * rng.uniform(0.5, 1.5, (3, n, n))
    weights = _weights(radius, kind)
    masks = rng.random((12, n, n)) < p
    crops = cc.choose_crops(radius, weights, PITCH, tolerance)
    exact = cn.resistance(masks, SpotGeometry.whole_window(radius, weights, PITCH), RHO, "direct").resistance
    cropped = cn.resistance(masks, SpotGeometry(radius, weights, PITCH, crops, tolerance), RHO)
    finite = np.isfinite(exact)
    error = np.abs(cropped.resistance[finite] / exact[finite] - 1.0)
    assert np.all(error <= tolerance)
    assert np.all(error <= cropped.crop_bound[finite] + 1e-13)
    assert np.all(cropped.crop_bound <= tolerance)


def test_crops_shrink_with_tolerance_and_vanish_at_zero():
    radius = _gaussian_spots(21, (1.0, 2.0, 5.0))
    assert list(cc.choose_crops(radius, radius, PITCH, 0.0)) == [21, 21, 21]
    loose = cc.choose_crops(radius, radius, PITCH, 1e-2)
    tight = cc.choose_crops(radius, radius, PITCH, 1e-8)
    assert np.all(loose <= tight) and loose[0] < 21
    assert np.all(np.diff(tight) >= 0)


def test_radius_crops_need_no_recomputation():
    """For radius weights the crop bound holds for every mask, so nothing falls back."""
    rng = np.random.default_rng(6)
    radius = _gaussian_spots(17, (1.0, 3.0))
    masks = rng.random((40, 17, 17)) < 0.05
    crops = cc.choose_crops(radius, radius, PITCH, 1e-6)
    assert cn.resistance(masks, SpotGeometry(radius, radius, PITCH, crops, 1e-6), RHO).n_uncropped == 0


def test_area_entries_above_tolerance_are_recomputed():
    """Only spots outside the crop conduct: the bound fails and the whole window is used."""
    radius = _gaussian_spots(15, (1.5,))
    weights = _weights(radius, "area")
    crops = cc.choose_crops(radius, weights, PITCH, 1e-6)
    assert crops[0] < 15
    c = cc.crop_slice(15, int(crops[0]))
    masks = np.ones((2, 15, 15), bool)
    masks[0, c, c] = False
    res = cn.resistance(masks, SpotGeometry(radius, weights, PITCH, crops, 1e-6), RHO)
    exact = cn.resistance(masks, SpotGeometry(radius, weights, PITCH, [15], 0.0), RHO, "direct")
    assert res.n_uncropped == 1
    assert res.resistance[0, 0] == pytest.approx(exact.resistance[0, 0], rel=1e-13)
    assert res.resistance[1, 0] == pytest.approx(exact.resistance[1, 0], rel=1e-6)


def test_interaction_weights_change_only_the_interaction_term():
    rng = np.random.default_rng(7)
    radius = _gaussian_spots(11, (1.0, 3.0))
    masks = rng.random((6, 11, 11)) < 0.5
    by_radius = cn.resistance(masks, SpotGeometry(radius, radius, PITCH, [11, 11], 0.0), RHO)
    by_area = cn.resistance(masks, SpotGeometry(radius, _weights(radius, "area"), PITCH, [11, 11], 0.0), RHO)
    np.testing.assert_array_equal(by_radius.resistance_self, by_area.resistance_self)
    assert not np.allclose(by_radius.resistance_interaction, by_area.resistance_interaction)


def test_greenwood_terms_open_and_single():
    r, r_self, r_int = cn.greenwood_terms([0.0, 2e-6], [0.0, 2e-6], [0.0, 0.0], [0, 1], RHO)
    assert np.isposinf(r[0]) and np.isposinf(r_self[0]) and np.isposinf(r_int[0])
    assert r_int[1] == 0.0 and r[1] == RHO / 4e-6


def test_padded_length_avoids_wrap():
    for n in (1, 2, 13, 57):
        assert fi.padded_length(n) >= 2 * n - 1


def test_unknown_method_is_rejected():
    with pytest.raises(ValueError, match="method"):
        ia.interaction_sum(np.zeros((1, 3, 3)), PITCH, "magic")


def test_auto_method_follows_the_measured_crossover():
    assert ia.auto_method(ia.FFT_FROM - 1) == "folded" and ia.auto_method(ia.FFT_FROM) == "fft"
    # blocks stay within the work budget at every size and keep the paper's 128 on small windows
    assert ia.block_size(57) == ia.BLOCK
    for n in (57, 229, 583, 1201):
        assert ia.block_size(n) * ia.work_bytes_per_map(n) <= max(ia.WORK_BYTES, ia.work_bytes_per_map(n))


@pytest.mark.parametrize("n", [ia.FFT_FROM - 2, ia.FFT_FROM])
def test_algorithm_choice_changes_nothing_beyond_1e_12(n):
    """Either side of the crossover, auto, folded and fft agree to 1e-12 (relative) per map and in R."""
    rng = np.random.default_rng(n)
    x = (np.arange(n) - n // 2) / (n // 2)
    radius = 1e-5 * np.exp(-4.0 * (x[None, :] ** 2 + x[:, None] ** 2))[None]
    masks = rng.random((3, n, n)) < 0.6
    u = masks * radius
    sums = {m: ia.interaction_sum(u, 2e-5, m) for m in ("auto", "folded", "fft")}
    for m in ("folded", "fft"):
        np.testing.assert_allclose(sums[m], sums["auto"], rtol=1e-12, atol=0)
    r = {m: cn.resistance(masks, SpotGeometry.whole_window(radius, radius, 2e-5), 7.2e-7, m).resistance
         for m in ("auto", "folded", "fft")}
    for m in ("folded", "fft"):
        np.testing.assert_allclose(r[m], r["auto"], rtol=1e-12, atol=0)


def test_truncation_bounds_match_choose_crops():
    rng = np.random.default_rng(3)
    n = 21
    x = np.arange(n) - n // 2
    a = 1e-5 * np.exp(-0.05 * (x[None, :] ** 2 + x[:, None] ** 2)) * rng.random((n, n))
    bounds = cc.truncation_bounds(a, a, 1e-4, 1.0)
    for tol in (1e-1, 1e-3, 1e-6):
        size = cc.choose_crops(a[None], a[None], 1e-4, tol)[0]
        k = int(np.flatnonzero(bounds <= tol)[0])
        assert size == 2 * k + 1
    # by hand: the square of side 2k+1 drops the weight outside it
    k = 4
    inner = a[n // 2 - k : n // 2 + k + 1, n // 2 - k : n // 2 + k + 1].sum()
    assert bounds[k] == pytest.approx(4.0 * (a.sum() - inner) / (np.pi * 1e-4), rel=1e-12)
    assert bounds[-1] == 0.0


def test_fft_padding_stays_zero_across_shapes():
    """The FFT path reuses zero-padded buffers: any sequence of shapes gives the exact sums."""
    rng = np.random.default_rng(11)
    for n, batch in [(40, 3), (38, 3), (40, 3), (40, 2), (25, 3), (40, 3)]:
        u = rng.random((batch, n, n)) * (rng.random((batch, n, n)) < 0.5)
        np.testing.assert_allclose(fi.interaction_fft(u, PITCH), fi.interaction_gemm(u, PITCH), rtol=1e-12)


def test_fft_filled_refuses_a_foreign_array():
    with pytest.raises(ValueError, match="fft_weights"):
        fi.interaction_fft_filled(np.ones((1, 9, 9)), PITCH)


def test_fft_steps_agree_with_the_folded_path_and_the_batch():
    """Crops either side of the crossover in one call (FFT steps run load step by load step,
    the others block by block), a short last block: per entry as the folded path, 1e-12."""
    rng = np.random.default_rng(8)
    n = ia.FFT_FROM + 8
    x = (np.arange(n) - n // 2) / (n // 2)
    decay = np.array([4.0, 3.0, 2.5, 2.0, 1.0])[:, None, None]
    radius = 1e-5 * np.exp(-decay * (x[None, :] ** 2 + x[:, None] ** 2)[None])
    crops = np.array([ia.FFT_FROM - 2, ia.FFT_FROM, n - 6, n - 4, n])
    masks = rng.random((ia.block_size(n) * 2 + 3, n, n)) < 0.6
    auto = cn.resistance(masks, SpotGeometry(radius, radius, 2e-5, crops, 1.0), 7.2e-7).resistance
    folded = cn.resistance(masks, SpotGeometry(radius, radius, 2e-5, crops, 1.0), 7.2e-7, "folded").resistance
    np.testing.assert_allclose(auto, folded, rtol=1e-12, atol=0)
    # the FFT steps are bit-identical whatever the batch (one transform per map; with fewer than
    # four load steps BLAS sums the spot counts by a kernel that depends on the row)
    fft = crops >= ia.FFT_FROM
    spots = SpotGeometry(radius[fft], radius[fft], 2e-5, crops[fft], 1.0)
    pieces = [cn.resistance(masks[i : i + 5], spots, 7.2e-7).resistance for i in range(0, masks.shape[0], 5)]
    whole = cn.resistance(masks, spots, 7.2e-7).resistance
    np.testing.assert_array_equal(np.concatenate(pieces), whole)


@pytest.mark.parametrize(("n", "method"), [(15, "auto"), (15, "direct"), (81, "auto")])
def test_per_map_spots_equal_one_call_per_map(n, method):
    """Groups (spots drawn per realization): each map equals a call with its own spots alone, within
    1e-12 (the FFT path from 75 cells, the folded one below), cropped or not, whatever the batch."""
    rng = np.random.default_rng(4)
    base = _gaussian_spots(n, (2.0, 4.0, 9.0))
    n_groups, batch = 3, 11
    radius = base[None] * (rng.random((n_groups, 1, n, n)) < 0.6) * rng.lognormal(0.0, 0.5, (n_groups, 1, n, n))
    masks = rng.random((batch, n, n)) < 0.7
    groups = rng.integers(0, n_groups, batch)
    crops = cc.choose_crops(base, base, PITCH, 1e-6)
    spots = SpotGeometry(radius, radius, PITCH, crops, 1e-6)
    got = cn.resistance(masks, spots, RHO, method, groups=groups)
    for b in range(batch):
        mine = radius[groups[b]]
        own = cn.resistance(masks[b : b + 1], SpotGeometry.whole_window(mine, mine, PITCH), RHO, "direct")
        assert _rel(got.resistance[b], own.resistance[0]) <= 1e-6  # the crop tolerance
        np.testing.assert_array_equal(got.n_conducting[b], own.n_conducting[0])
    # a map's result does not depend on the others in its batch
    order = rng.permutation(batch)
    again = cn.resistance(masks[order], spots, RHO, method, groups=groups[order])
    np.testing.assert_array_equal(again.resistance, got.resistance[order])
    first = cn.resistance(masks[:4], spots, RHO, method, groups=groups[:4])
    np.testing.assert_array_equal(first.resistance, got.resistance[:4])
