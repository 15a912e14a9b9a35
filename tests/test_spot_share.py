"""The disc spot rule (g2tom.physics.spot_share) and the field at arbitrary points (oxide_points)."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.physics import oxide_band as ob
from g2tom.physics import oxide_field as of
from g2tom.physics.oxide_points import values_at_points
from g2tom.physics.spot_share import DEFAULT_RINGS, DiscRule, disc_points, disc_shares, effective_radius
from tests.oracles import clean_share, spot_points

N_CELLS = 57  # the paper scenario's window
CELL = 1.0 / np.sqrt(2e8)  # m


def _paper_band(lam: float) -> ob.Band:
    """The paper scene's band at lambda, on the spectral period of resolution 16."""
    return ob.band(N_CELLS, CELL, lam, 3.0, 0.5, ob.spectral_period(N_CELLS, lam, 16))


def _coeffs(modes: ob.Band, lam: float, count: int, seed: int = 7) -> np.ndarray:
    return np.stack([ob.coefficients(modes, ob.field_stream(seed, lam, r)) for r in range(count)])


@pytest.mark.parametrize("lam, spectral", [(1.0, False), (5.0, True), (23.0, True)])
def test_values_at_points_equal_direct_sum(lam: float, spectral: bool) -> None:
    modes = _paper_band(lam) if spectral else ob.band(N_CELLS, CELL, lam, 3.0, 0.5)
    coeffs = _coeffs(modes, lam, 6).reshape(2, 3, -1)  # any leading shape
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-40 * CELL, 40 * CELL, (2, 5, 140))  # also outside the window
    values = values_at_points(modes, coeffs, x, y)
    assert values.shape == (2, 3, 5, 140) and values.dtype == np.float64
    for b in np.ndindex(2, 3):
        # unit-variance fields: atol 1e-12 covers values near 0, where rtol means nothing
        np.testing.assert_allclose(values[b], of.field_at_points(modes, coeffs[b], x, y), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("periods", [0.3, 1.4, 7.0])
def test_values_at_points_beyond_three_pi_are_wrapped_into_the_period(periods: float) -> None:
    """Phases within [-3 pi, 3 pi) go to FINUFFT as they are, others are wrapped first: both equal
    the direct sum, and a point a whole number of periods away gives the same value."""
    modes = ob.band(N_CELLS, CELL, 1.0, 3.0, 0.5)  # period = the window: 40 cells out is past 3 pi at 1.4
    coeffs = _coeffs(modes, 1.0, 1)[0]
    x = np.linspace(-periods, periods, 701) * modes.period
    y = 0.3 * x
    values = values_at_points(modes, coeffs, x, y)
    np.testing.assert_allclose(values, of.field_at_points(modes, coeffs, x, y), rtol=1e-10, atol=1e-11)
    shifted = values_at_points(modes, coeffs, x + 3 * modes.period, y - 2 * modes.period)
    np.testing.assert_allclose(shifted, values, rtol=0, atol=1e-10)


def test_unsorted_points_give_the_sorted_transforms_values_bit_for_bit() -> None:
    import finufft

    from g2tom.physics import oxide_points

    modes = _paper_band(1.0)
    coeffs = _coeffs(modes, 1.0, 3)
    rng = np.random.default_rng(5)
    x, y = rng.uniform(-25 * CELL, 25 * CELL, (2, 400))
    px, py = disc_points(x, y, rng.uniform(0.0, 0.2 * CELL, (3, 400)), np.full((3, 400), DEFAULT_RINGS))
    values = values_at_points(modes, coeffs, px, py, 1e-7)
    size = 2 * int(max(np.abs(modes.i).max(), modes.j.max())) + 2
    plan = finufft.Plan(2, (size, size), eps=1e-7, isign=1, nthreads=1)  # FINUFFT's default: points sorted
    scale = 2.0 * np.pi / modes.period
    plan.setpts(oxide_points._phases(scale, py), oxide_points._phases(scale, px))
    for b in range(3):
        table = np.zeros((size, size), dtype=complex)
        table[modes.j + size // 2, modes.i + size // 2] = coeffs[b]
        np.testing.assert_array_equal(values[b], plan.execute(table).real)


def test_values_at_points_of_many_fields_and_one_field() -> None:
    modes = _paper_band(5.0)
    coeffs = _coeffs(modes, 5.0, 40)
    x = np.linspace(-20 * CELL, 20 * CELL, 3001)
    values = values_at_points(modes, coeffs, x, 0.5 * x)
    single = values_at_points(modes, coeffs[17], x, 0.5 * x)
    assert single.shape == x.shape
    np.testing.assert_allclose(values[17], single, rtol=0, atol=1e-12)
    np.testing.assert_allclose(single[::97], of.field_at_points(modes, coeffs[17], x[::97], 0.5 * x[::97]),
                               rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("n_rings", [0, 1, 3, DEFAULT_RINGS])
def test_pattern_is_an_equal_area_partition(n_rings: int) -> None:
    rule = DiscRule(n_rings)
    u, v = rule.offsets()
    w = rule.weights()
    assert u.shape == v.shape == w.shape == (1 + 3 * n_rings * (n_rings + 1),)
    assert w.sum() == pytest.approx(1.0, abs=1e-14)
    assert np.all(u**2 + v**2 < 1.0)
    assert abs(w @ u) < 1e-14 and abs(w @ v) < 1e-14  # every ring sums to zero
    # second moments of the unit disc (1/4 per axis) but for the centre cell's 1/(4 N^2)
    expect = 0.25 * (1.0 - 1.0 / rule.size**2) if n_rings else 0.0
    assert w @ u**2 == pytest.approx(expect, abs=1e-14)
    assert w @ v**2 == pytest.approx(expect, abs=1e-14)
    assert abs(w @ (u * v)) < 1e-14


def test_default_second_moment_is_the_disc_s() -> None:
    u, v = DiscRule().offsets()
    assert DiscRule().weights() @ (u**2 + v**2) == pytest.approx(0.5, abs=1e-4)


def test_bad_ring_count() -> None:
    for bad in (-1, 2.5):
        with pytest.raises(ValueError, match="n_rings"):
            DiscRule(bad)


def test_spot_points_scale_the_pattern() -> None:
    rule = DiscRule(2)
    u, v = rule.offsets()
    x, y = spot_points(np.array([1e-6, -2e-6]), np.array([0.0, 3e-6]), np.array([1e-7, 4e-7]), rule)
    assert x.shape == y.shape == (2, rule.size)
    np.testing.assert_allclose(x[1], -2e-6 + 4e-7 * u, rtol=1e-15, atol=0)
    np.testing.assert_allclose(y[0], 1e-7 * v, rtol=1e-15, atol=0)


def test_disc_inside_clean_or_oxide_gives_one_or_zero() -> None:
    lam = 5.0
    modes = _paper_band(lam)
    coeffs = _coeffs(modes, lam, 1)[0]
    rule = DiscRule()
    # the field's extremes on the cell centres; a tiny disc there lies on one side of any
    # threshold between the extreme and 0
    grid = of.centre_values(modes, coeffs, N_CELLS, CELL)
    centres = (np.arange(N_CELLS) - (N_CELLS - 1) / 2) * CELL
    hi, lo = np.unravel_index(grid.argmax(), grid.shape), np.unravel_index(grid.argmin(), grid.shape)
    xc = centres[[hi[1], lo[1]]]
    yc = centres[[hi[0], lo[0]]]
    x, y = spot_points(xc, yc, np.full(2, 0.01 * lam * CELL), rule)
    values = values_at_points(modes, coeffs, x, y)
    f = clean_share(values, 0.0, rule.weights())
    assert values[0].min() > 0 > values[1].max()
    np.testing.assert_array_equal(f, [0.0, 1.0])  # oxide on the peak, clean in the trough


def _fine_share(modes: ob.Band, coeffs: np.ndarray, xc: float, yc: float, a: float,
                thresholds: np.ndarray) -> np.ndarray:
    """Clean share of the disc from a 200 x 200 image of its bounding square (pixel centres)."""
    t = (np.arange(200) + 0.5) / 100.0 - 1.0
    image = of.grid_values(modes, coeffs, xc + a * t, yc + a * t)
    inside = (t[None, :] ** 2 + t[:, None] ** 2) <= 1.0
    return np.array([np.mean(image[inside] < th) for th in thresholds])


@pytest.mark.parametrize("lam", [1.0, 5.0, 23.0])
def test_clean_share_converges_to_fine_image(lam: float) -> None:
    modes = _paper_band(lam)
    coeffs = _coeffs(modes, lam, 1)[0]
    rng = np.random.default_rng(1)
    xc, yc = rng.uniform(-20 * CELL, 20 * CELL, (2, 30))
    a = np.full(30, lam * CELL / 2)  # half the correlation length
    thresholds = of.theoretical_threshold(np.array([0.3, 0.5, 0.7]))
    fine = np.stack([_fine_share(modes, coeffs, xc[s], yc[s], a[s], thresholds) for s in range(30)], axis=1)
    assert np.mean((fine > 0) & (fine < 1)) > 0.9  # the discs are cut by oxide edges
    mean_error = []
    for n_rings in (1, 2, 4, DEFAULT_RINGS):
        rule = DiscRule(n_rings)
        x, y = spot_points(xc, yc, a, rule)
        f = clean_share(values_at_points(modes, coeffs, x, y), thresholds[:, None, None], rule.weights())
        error = np.abs(f - fine)
        mean_error.append(error.mean())
    assert np.all(np.diff(mean_error) < 0)
    assert mean_error[-1] < 0.01
    assert error.max() < 0.02  # every disc, every threshold, at the default pattern


def test_clean_share_shapes_and_broadcast_thresholds() -> None:
    rule = DiscRule(1)
    values = np.arange(2 * 3 * 7, dtype=float).reshape(2, 3, 7) - 20.5  # (field, spot, point)
    f = clean_share(values[None], np.array([-100.0, 0.0, 100.0])[:, None, None, None], rule.weights())
    assert f.shape == (3, 2, 3)
    np.testing.assert_array_equal(f[0], 0.0)
    np.testing.assert_array_equal(f[2], 1.0)
    np.testing.assert_allclose(f[1], np.mean(values < 0, axis=-1), rtol=1e-15)


def test_centre_rule_and_full_share_keep_the_radius() -> None:
    lam = 5.0
    modes = _paper_band(lam)
    coeffs = _coeffs(modes, lam, 3)
    rng = np.random.default_rng(5)
    xc, yc = rng.uniform(-20 * CELL, 20 * CELL, (2, 50))
    a = rng.uniform(0.1, 1.0, 50) * CELL
    rule = DiscRule(0)
    x, y = spot_points(xc, yc, a, rule)
    np.testing.assert_array_equal(x[:, 0], xc)
    f = clean_share(values_at_points(modes, coeffs, x, y), 0.2, rule.weights())
    centre_clean = of.field_at_points(modes, coeffs[1], xc, yc) < 0.2
    np.testing.assert_array_equal(f[1], centre_clean.astype(float))
    radius = effective_radius(a, f)
    np.testing.assert_array_equal(radius[1], np.where(centre_clean, a, 0.0))  # f = 1: the spot's own radius
    np.testing.assert_allclose(effective_radius(a, 0.25), a / 2, rtol=1e-15)


def test_compiled_disc_points_and_shares_equal_the_spot_by_spot_definition() -> None:
    lam = 3.0
    modes = _paper_band(lam)
    coeffs = _coeffs(modes, lam, 1)[0]
    rng = np.random.default_rng(12)
    n, steps = 40, 5
    xc, yc = rng.uniform(-20 * CELL, 20 * CELL, (2, n))
    radius = rng.uniform(0.0, 0.6 * lam * CELL, (steps, n)) * (rng.uniform(size=(steps, n)) > 0.3)
    rings = rng.integers(0, DEFAULT_RINGS + 1, (steps, n))
    thresholds = of.theoretical_threshold(np.array([0.1, 0.5, 0.9])).astype(np.float32)
    px, py = disc_points(xc, yc, radius, rings)
    values = values_at_points(modes, coeffs, px, py).astype(np.float32)
    shares = disc_shares(values, thresholds, radius, rings)
    assert shares.shape == (3, steps, n)
    start = 0
    for d, i in zip(*np.nonzero(radius > 0)):  # (step, spot) order
        rule = DiscRule(int(rings[d, i]))
        x, y = spot_points(xc[i:i + 1], yc[i:i + 1], radius[d, i:i + 1], rule)
        np.testing.assert_array_equal(px[start:start + rule.size], x[0])
        np.testing.assert_array_equal(py[start:start + rule.size], y[0])
        block = values[start:start + rule.size]
        start += rule.size
        want = clean_share(block[None], thresholds[:, None], rule.weights())
        np.testing.assert_allclose(shares[:, d, i], want, rtol=1e-14, atol=0)
    assert start == px.size
    assert np.all(shares[:, radius == 0] == 0.0)
    assert 0 < np.mean((shares > 0) & (shares < 1))  # some discs are cut


def test_disc_rings_out_of_range_are_refused() -> None:
    with pytest.raises(ValueError, match="rings"):
        disc_points(np.zeros(2), np.zeros(2), np.ones((1, 2)), np.full((1, 2), DEFAULT_RINGS + 1))
    with pytest.raises(ValueError, match="rings"):
        disc_points(np.zeros(2), np.zeros(2), np.ones((1, 2)), np.zeros((2, 2)))


def test_segment_rule_lies_between_the_equal_area_disc_and_the_whole_disc():
    """h(f) >= sqrt(f) (the disc has the least capacity of its area), <= 1 (a part of the disc
    conducts less than all of it), increasing in f, equal to both at f = 0 and 1."""
    from g2tom.physics.spot_share import SEGMENT_GAIN, SEGMENT_SHARE

    shares, gains = np.array(SEGMENT_SHARE), np.array(SEGMENT_GAIN)
    assert np.all(np.diff(shares) > 0) and np.all(np.diff(gains) <= 0) and gains[-1] == 1.0 and shares[-1] == 1.0
    f = np.linspace(0.0, 1.0, 2001)
    a = 7e-6
    segment, disc = effective_radius(a, f, "segment"), effective_radius(a, f, "disc")
    assert np.all(segment >= disc) and np.all(segment <= a * (1 + 1e-12)) and np.all(np.diff(segment) > 0)
    assert segment[0] == 0.0 and segment[-1] == a
    np.testing.assert_allclose(effective_radius(a, 0.5, "segment") / effective_radius(a, 0.5, "disc"), 1.0414)
    np.testing.assert_array_equal(effective_radius(a, np.array([0.0, 1.0]), "centre"), [0.0, a])
    with pytest.raises(ValueError, match="rule = 'ring'"):
        effective_radius(a, f, "ring")


def test_segment_table_is_the_full_fields_flat_punch():
    """The table against the reference's own flat punch on a coarser grid (60 pixels of radius on
    128^2; the table: 80 pixels on 256^2): within 0.2 % from f = 0.19, within 1.5 % on the thin
    segment (f 0.03, 8 pixels thick here: -3.1 % on 40 pixels, -1.05 % on 60, converging)."""
    from g2tom.physics.spot_share import SEGMENT_GAIN, SEGMENT_SHARE
    from g2tom.reference.segment import segment_gains

    shares, gains = segment_gains(radius=60.0, n=128, chords=5, tolerance=1e-8)
    assert shares.size == 5 and np.all(np.diff(shares) > 0) and shares[0] < 0.05 < shares[1]
    table = np.interp(shares, SEGMENT_SHARE, SEGMENT_GAIN)
    np.testing.assert_allclose(gains[1:], table[1:], rtol=0.002)
    np.testing.assert_allclose(gains[0], table[0], rtol=0.015)
