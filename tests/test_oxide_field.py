"""Oxide random fields (g2tom.physics.oxide_band, oxide_field): exact point values, spectrum, statistics."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from g2tom.physics import oxide_band as ob
from g2tom.physics import oxide_field as of
from g2tom.physics.grid import cell_centres
from tests.oracles import fine_grid

N_CELLS = 57  # the paper scenario's window
CELL = 1.0 / np.sqrt(2e8)  # m
STRIDE = 18  # 57 * 18 = 1026 pixels: the fine image contains every cell centre


def _fields(lam: float, count: int, *, hurst: float = 0.5, amplitudes: str = "ideal", seed: int = 11):
    modes = ob.band(N_CELLS, CELL, lam, 3.0, hurst)
    coeffs = np.stack(
        [ob.coefficients(modes, ob.field_stream(seed, lam, r), amplitudes) for r in range(count)]
    )
    return modes, coeffs


def _at_centres(image: np.ndarray) -> np.ndarray:
    """Fine-image pixels at the cell centres (pixel q * STRIDE is centre offset q mod n)."""
    take = np.fft.fftshift(np.arange(N_CELLS) * STRIDE)
    return image[..., take[:, None], take[None, :]]


# ------------------------------------------------------------------ exact point values
@pytest.mark.parametrize("amplitudes", ["ideal", "rayleigh"])
@pytest.mark.parametrize("lam", [1.0, 1.37, 2.0, 7.0])
def test_cell_values_equal_fine_synthesis_at_centres(lam: float, amplitudes: str) -> None:
    modes, coeffs = _fields(lam, 2, amplitudes=amplitudes)
    fine = fine_grid(modes, coeffs, N_CELLS * STRIDE)
    np.testing.assert_allclose(of.cell_values(modes, coeffs, N_CELLS), _at_centres(fine), rtol=0, atol=1e-12)


def test_folding_is_needed_above_nyquist() -> None:
    """Negative control: dropping the modes above the cell grid's Nyquist index is far off at lambda = 1."""
    modes, coeffs = _fields(1.0, 1)
    assert np.abs(modes.i).max() > N_CELLS // 2  # the band really reaches past Nyquist
    below = (np.abs(modes.i) <= N_CELLS // 2) & (modes.j <= N_CELLS // 2)
    naive = ob.Band(modes.i[below], modes.j[below], modes.weight[below], modes.period)
    exact = of.cell_values(modes, coeffs, N_CELLS)
    assert np.abs(of.cell_values(naive, coeffs[:, below], N_CELLS) - exact).max() > 0.5


def test_point_evaluation_matches_1024_image_where_pixels_lie() -> None:
    modes, coeffs = _fields(1.0, 1)
    image = fine_grid(modes, coeffs, 1024)[0]
    rng = np.random.default_rng(0)
    a, b = rng.integers(0, 1024, (2, 300))
    pixel = modes.period / 1024
    direct = of.field_at_points(modes, coeffs[0], b * pixel, a * pixel)
    np.testing.assert_allclose(direct, image[a, b], rtol=0, atol=1e-11)


def test_point_evaluation_equals_cell_values_at_centres() -> None:
    modes, coeffs = _fields(1.0, 1)
    x = cell_centres(N_CELLS, CELL)
    direct = of.field_at_points(modes, coeffs[0], x[None, :], x[:, None])
    np.testing.assert_allclose(of.cell_values(modes, coeffs, N_CELLS)[0], direct, rtol=0, atol=1e-11)


# ------------------------------------------------------------------ spectrum and variance
def _mode_power(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ensemble power of every lattice mode of cell-grid fields, and the mode's |k| in lattice steps."""
    power = (np.abs(np.fft.fft2(values, norm="forward")) ** 2).mean(axis=0)
    q = np.fft.fftfreq(N_CELLS, 1.0 / N_CELLS)
    return power, np.hypot(q[:, None], q[None, :])


def _radial_average(power: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean |k| and mean power over unit-wide rings of the given modes."""
    rings = np.rint(radius).astype(int)
    count = np.bincount(rings)
    used = count > 0
    return np.bincount(rings, radius)[used] / count[used], np.bincount(rings, power)[used] / count[used]


@pytest.mark.parametrize("amplitudes", ["ideal", "rayleigh"])
@pytest.mark.parametrize("hurst", [0.5, 0.2])
def test_power_spectrum_band_and_slope(hurst: float, amplitudes: str) -> None:
    lam = 4.0  # ks = 21.4 lattice steps, below the cell grid's Nyquist index 28.5
    modes, coeffs = _fields(lam, 60, hurst=hurst, amplitudes=amplitudes)
    power, radius = _mode_power(of.cell_values(modes, coeffs, N_CELLS))
    k1 = N_CELLS / (2 * lam)
    inside = (radius >= k1) & (radius <= 3 * k1)
    assert power[~inside].max() < 1e-25 * power[inside].mean()  # nothing outside the band
    assert np.all(power[inside] > 0)  # every lattice mode of the band is present
    ring_k, ring_power = _radial_average(power[inside], radius[inside])
    slope = np.polyfit(np.log(ring_k), np.log(ring_power), 1)[0]
    assert slope == pytest.approx(-2 * (1 + hurst), abs=0.02 if amplitudes == "ideal" else 0.2)


def test_band_edges_are_inclusive() -> None:
    """k1 <= |k| <= ks with both cut-offs on lattice radii: 15 cells, lambda = 1.5 -> k1 = 5, ks = 15."""
    modes = ob.band(15, CELL, 1.5, 3.0, 0.5)
    j, i = np.meshgrid(np.arange(0, 16), np.arange(-15, 16), indexing="ij")
    r2 = i**2 + j**2  # exact integers: no rounding at the edges
    keep = ((j > 0) | (i > 0)) & (r2 >= 5**2) & (r2 <= 15**2)
    expected = set(zip(i[keep].tolist(), j[keep].tolist()))
    assert set(zip(modes.i.tolist(), modes.j.tolist())) == expected
    assert {(5, 0), (3, 4), (0, 5), (15, 0), (9, 12), (-12, 9)} <= expected


@pytest.mark.parametrize("amplitudes", ["ideal", "rayleigh"])
@pytest.mark.parametrize("lam", [1.0, 5.0, 23.0])
def test_unit_variance_over_the_window(lam: float, amplitudes: str) -> None:
    modes, coeffs = _fields(lam, 3, amplitudes=amplitudes)
    fine = fine_grid(modes, coeffs, 228)
    np.testing.assert_allclose(fine.std(axis=(-2, -1)), 1.0, atol=1e-12)
    np.testing.assert_allclose(fine.mean(axis=(-2, -1)), 0.0, atol=1e-12)


@pytest.mark.parametrize("lam", [1.0, 3.0])
def test_cell_values_have_unit_ensemble_variance(lam: float) -> None:
    modes, coeffs = _fields(lam, 200)
    second_moment = (of.cell_values(modes, coeffs, N_CELLS) ** 2).mean(axis=(-2, -1))
    standard_error = second_moment.std(ddof=1) / np.sqrt(second_moment.size)
    assert abs(second_moment.mean() - 1.0) < 4 * standard_error + 1e-12


def test_indicator_correlation_length_scales_with_lambda() -> None:
    """The 1/e length of the indicator's radial autocorrelation doubles when lambda doubles."""
    pixels = 4 * N_CELLS  # resolve the short lengths at lambda = 2

    def length(lam: float) -> float:
        modes, coeffs = _fields(lam, 20)
        indicator = (fine_grid(modes, coeffs, pixels) >= 0).astype(float)
        indicator -= indicator.mean(axis=(-2, -1), keepdims=True)
        acf = np.fft.irfft2(np.abs(np.fft.rfft2(indicator)) ** 2, s=(pixels, pixels)).mean(axis=0)
        q = np.fft.fftfreq(pixels, 1.0 / pixels)
        rings = np.rint(np.hypot(q[:, None], q[None, :])).astype(int).ravel()
        profile = np.bincount(rings, acf.ravel()) / np.bincount(rings) / acf[0, 0]
        k = int(np.argmax(profile < np.exp(-1)))
        return k - 1 + (profile[k - 1] - np.exp(-1)) / (profile[k - 1] - profile[k])

    lengths = np.array([length(lam) for lam in (2.0, 4.0, 8.0)])
    np.testing.assert_allclose(lengths[1:] / lengths[:-1], 2.0, rtol=0.12)


# ------------------------------------------------------------------ thresholds and streams
def test_theoretical_threshold_is_the_gaussian_quantile() -> None:
    xi = np.array([0.1, 0.2, 0.5, 0.9])
    psi0 = of.theoretical_threshold(xi)
    np.testing.assert_allclose(norm.sf(psi0), xi, rtol=1e-12)
    assert psi0[2] == 0.0 and psi0[0] > 0 > psi0[3]


@pytest.mark.parametrize("xi", [[0.0, 0.5], [0.5, 1.0], [-0.1]])
def test_theoretical_threshold_rejects_fractions_outside_0_1(xi: list[float]) -> None:
    with pytest.raises(ValueError, match="xi"):
        of.theoretical_threshold(np.array(xi))


def test_empirical_threshold_covers_exactly_round_xi_n() -> None:
    modes, coeffs = _fields(5.0, 4)
    values = of.cell_values(modes, coeffs, N_CELLS).astype(np.float32).reshape(4, -1)
    xi = np.array([0.1, 0.25, 0.5, 0.9, 1e-5])
    threshold = of.empirical_threshold(values, xi)
    assert threshold.shape == (5, 4) and threshold.dtype == np.float32
    counts = (values[None] >= threshold[..., None]).sum(axis=-1)
    expected = np.rint(xi * values.shape[-1]).astype(int)
    np.testing.assert_array_equal(counts, np.broadcast_to(expected[:, None], counts.shape))
    assert np.all(np.isinf(threshold[-1]))  # round(1e-5 N) = 0 cells: nothing is covered


def test_streams_are_keyed_on_lambda_value_and_realization() -> None:
    def draw(lam: float, r: int, seed: int = 5) -> np.ndarray:
        return ob.field_stream(seed, lam, r).random(4)

    np.testing.assert_array_equal(draw(3.0, 7), draw(3.0, 7))
    distinct = [draw(3.0, 7), draw(3.0, 8), draw(5.0, 7), draw(3.0, 7, seed=6)]
    assert len({d.tobytes() for d in distinct}) == len(distinct)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"lam": 0.0}, "lambda"),
        ({"lam": -2.0}, "lambda"),
        ({"hurst": 1.0}, "hurst"),
        ({"hurst": 0.0}, "hurst"),
        ({"ks_ratio": 1.0}, "ks_ratio"),
        ({"lam": 500.0}, "no Fourier mode"),
        ({"n_cells": 56}, "n_cells"),
    ],
)
def test_band_rejects_bad_parameters(kwargs: dict, name: str) -> None:
    args = {"n_cells": N_CELLS, "cell_size": CELL, "lam": 2.0, "ks_ratio": 3.0, "hurst": 0.5} | kwargs
    with pytest.raises(ValueError, match=name):
        ob.band(**args)


def test_unknown_amplitude_model_is_rejected() -> None:
    modes = ob.band(N_CELLS, CELL, 5.0, 3.0, 0.5)
    with pytest.raises(ValueError, match="amplitudes"):
        ob.coefficients(modes, ob.field_stream(0, 5.0, 0), "gaussian")


# ------------------------------------------------------------------ spectral period
def _spectral(lam: float, count: int, resolution: float, n_cells: int = N_CELLS, amplitudes: str = "ideal"):
    period = ob.spectral_period(n_cells, lam, resolution)
    modes = ob.band(n_cells, CELL, lam, 3.0, 0.5, period)
    coeffs = np.stack(
        [ob.coefficients(modes, ob.field_stream(5, lam, r), amplitudes) for r in range(count)]
    )
    return period, modes, coeffs


@pytest.mark.parametrize("lam", [3.0, 13.0, 23.0])
def test_centre_values_equal_direct_summation(lam: float) -> None:
    _, modes, coeffs = _spectral(lam, 2, 7.0)
    x = cell_centres(N_CELLS, CELL)
    direct = of.field_at_points(modes, coeffs[1], x[None, :], x[:, None])
    np.testing.assert_allclose(of.centre_values(modes, coeffs, N_CELLS, CELL)[1], direct, rtol=0, atol=1e-11)


def test_spectral_period_grows_with_lambda_and_keeps_thousands_of_modes() -> None:
    sizes = []
    for lam in (1.0, 13.0, 15.0, 21.0, 23.0, 50.0):
        period = ob.spectral_period(N_CELLS, lam, 16.0)
        assert period >= N_CELLS and period / (2 * lam) >= 16.0
        sizes.append(ob.band(N_CELLS, CELL, lam, 3.0, 0.5, period).size)
    assert min(sizes) > 3000  # against 20 .. 62 modes on the window's lattice at lambda 13 .. 23


@pytest.mark.parametrize("amplitudes", ["ideal", "rayleigh"])
def test_realized_spectrum_matches_phi_on_the_annulus(amplitudes: str) -> None:
    """Periodogram over one whole period (averaged over realizations) against Phi(k) = k^-3."""
    lam, resolution = 5.0, 6.0
    period, modes, coeffs = _spectral(lam, 300, resolution, n_cells=15, amplitudes=amplitudes)
    values = of.centre_values(modes, coeffs, period, CELL)  # every lattice point of the period
    power = (np.abs(np.fft.fft2(values, norm="forward")) ** 2).mean(axis=0)
    q = np.fft.fftfreq(period, 1.0 / period)
    radius = np.hypot(q[:, None], q[None, :])
    k1 = period / (2 * lam)
    inside = (radius >= k1) & (radius <= 3 * k1)
    assert power[~inside].max() < 1e-20  # nothing outside the band
    # |c|^2 / 4 on each of the two Hermitian partners; Phi normalized to unit variance
    phi = radius[inside] ** -3.0
    expected = phi / phi.sum()
    rings = np.rint(radius[inside] / 2).astype(int)
    used = np.bincount(rings) > 0
    got = np.bincount(rings, power[inside])[used] / np.bincount(rings, expected)[used]
    tolerance = 1e-12 if amplitudes == "ideal" else 0.1
    np.testing.assert_allclose(got, 1.0, atol=tolerance)
    assert power.sum() == pytest.approx(1.0, abs=1e-12 if amplitudes == "ideal" else 0.05)


@pytest.mark.parametrize("lam", [1.0, 23.0, 50.0])
def test_unit_variance_and_xi_quantile_at_the_cell_centres(lam: float) -> None:
    """Ensemble variance 1 and P(psi >= psi0(xi)) = xi at every lambda, also far above the window."""
    _, modes, coeffs = _spectral(lam, 400, 16.0)
    values = (of.centre_values(modes, coeffs, N_CELLS, CELL) if modes.period > N_CELLS * CELL
              else of.cell_values(modes, coeffs, N_CELLS))
    per_field = values.reshape(values.shape[0], -1)
    # realizations are independent; cells within one are not: errors from the spread of field means
    second = (per_field**2).mean(axis=1)
    assert abs(second.mean() - 1.0) < 4 * second.std(ddof=1) / np.sqrt(second.size) + 1e-3
    for xi in (0.1, 0.5, 0.9):
        share = (per_field >= of.theoretical_threshold(np.array(xi))).mean(axis=1)
        assert abs(share.mean() - xi) < 4 * share.std(ddof=1) / np.sqrt(share.size) + 1e-3
