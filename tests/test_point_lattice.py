"""The point model's lattice self term and radius floor; Barber's theorem for expected spots."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.physics import constriction, point_model
from g2tom.physics.crops import choose_crops
from g2tom.physics.lattice import SQUARE_LATTICE_CONSTANT
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.stages import contact
from tests.test_point_model import PITCH, RHO, _random_case, _whole



@pytest.mark.parametrize("film", [np.inf, 3e-11])
def test_lattice_term_matches_the_dense_solve(film):
    """Matrix-free with the lattice term against the dense Cholesky solve of the same M."""
    masks, radius = _random_case(4)
    c = SQUARE_LATTICE_CONSTANT
    res = point_model.resistance(masks, _whole(radius), RHO,
                                 film_resistance=film, lattice_constant=c)
    dense, _ = point_model.resistance_dense(masks, radius, PITCH, RHO, film, lattice_constant=c)
    plain, _ = point_model.resistance_dense(masks, radius, PITCH, RHO, film)
    finite = np.isfinite(dense)
    assert np.array_equal(finite, np.isfinite(res.resistance)) and finite.any()
    assert np.max(np.abs(res.resistance[finite] / dense[finite] - 1)) <= 1e-10
    assert np.all(dense[finite] > plain[finite] * (1 + 1e-3))  # the term raises every M_ii


def test_lattice_term_of_one_spot_is_in_series():
    """One spot: R = rho* (1/(2a) + C/(pi dx)), the term in series with the spot's own resistance."""
    radius = np.zeros((1, 5, 5))
    radius[0, 2, 1] = 4e-6
    res = point_model.resistance(np.ones((1, 5, 5), bool), _whole(radius), RHO,
                                 lattice_constant=2.5)
    assert res.resistance[0, 0] == pytest.approx(RHO * (1 / 8e-6 + 2.5 / (np.pi * PITCH)), rel=1e-14)


@pytest.mark.parametrize("value", [-1.0, np.nan, np.inf])
def test_bad_lattice_constant_is_refused(value):
    masks, radius = _random_case(0, n=3, n_delta=1, batch=1)
    with pytest.raises(ValueError, match=f"lattice_constant = {value!r} is out of range"):
        point_model.resistance(masks, _whole(radius), RHO, lattice_constant=value)
    with pytest.raises(ValueError, match="lattice_constant"):
        point_model.resistance_dense(masks, radius, PITCH, RHO, lattice_constant=value)


@pytest.mark.parametrize("film", [np.inf, 0.0, 3e-11])
@pytest.mark.parametrize("lattice_constant", [0.0, SQUARE_LATTICE_CONSTANT])
def test_vanishing_radii_count_as_no_spot(film, lattice_constant):
    """Radii of 1e-323 m (1/(2a) overflows) give the result of the map without those spots."""
    masks, radius = _random_case(7, n=11)
    tiny = (radius == 0) & (np.arange(11) % 2 == 0)[None, None, :]
    floored = np.where(tiny, 1e-323, radius)
    floored[0, :, :] = np.where(radius[0] > 0, 1e-323, 0.0)  # a step where every spot vanishes
    removed = np.where(floored == 1e-323, 0.0, floored)
    # the crop is the whole window, so the tiny spots are inside the solve
    kwargs = {"film_resistance": film, "lattice_constant": lattice_constant}
    got = point_model.resistance(masks, SpotGeometry.whole_window(floored, floored, PITCH), RHO, **kwargs)
    want = point_model.resistance(masks, SpotGeometry.whole_window(removed, removed, PITCH), RHO, **kwargs)
    assert not np.isnan(got.resistance).any() and np.all(np.isinf(got.resistance[:, 0]))
    np.testing.assert_allclose(got.resistance, want.resistance, rtol=1e-12)
    np.testing.assert_array_equal(got.n_conducting, want.n_conducting)
    dense, greenwood = point_model.resistance_dense(masks, floored, PITCH, RHO, film,
                                                    lattice_constant=lattice_constant)
    np.testing.assert_allclose(dense, want.resistance, rtol=1e-10)
    assert not np.isnan(greenwood).any()


def test_greenwood_closed_form_with_vanishing_radii_is_finite():
    masks, radius = _random_case(8, n=11)
    floored = np.where(radius == 0, 1e-323, radius)
    removed = point_model.greenwood_resistance(masks, _whole(radius), RHO,
                                               film_resistance=3e-11)
    got = point_model.greenwood_resistance(masks, SpotGeometry.whole_window(floored, floored, PITCH), RHO,
                                           film_resistance=3e-11)
    np.testing.assert_allclose(got.resistance, removed.resistance, rtol=1e-12)
    insulating = constriction.resistance(masks, SpotGeometry.whole_window(floored, floored, PITCH), RHO)
    plain = constriction.resistance(masks, _whole(radius), RHO)
    np.testing.assert_allclose(insulating.resistance, plain.resistance, rtol=1e-12)


def test_expected_spots_with_the_lattice_term_obey_barber(paper_gt):
    """Clean paper scene: the contact stage's expected spots (radius sqrt(beta) F_1/2(h) per cell)
    conduct K / (E* rho*) (Barber, K from the linearised Greenwood-Tripp system) to 1e-4 at every step
    with the lattice term (measured 2e-5), and 0.5-3.4 % too much without it."""
    ds = contact.build(paper_gt)  # the stage's expected spots and its Barber conductance
    assert paper_gt.contact.spots == "expected"
    barber = ds["barber_conductance"].values * RHO  # conductance x rho*, m
    radius, dx = ds["spot_radius"].values, paper_gt.cell_size
    masks = np.ones((1, paper_gt.n_cells, paper_gt.n_cells), bool)
    crops = choose_crops(radius, radius, dx, 1e-9)

    def conductance(c):
        res = point_model.resistance(masks, SpotGeometry(radius, radius, dx, crops, 1e-9), RHO, lattice_constant=c)
        return RHO / res.resistance[0]

    assert np.max(np.abs(conductance(SQUARE_LATTICE_CONSTANT) / barber - 1)) < 1e-4
    assert np.min(conductance(0.0) / barber - 1) > 4e-3


@pytest.mark.parametrize("film", [np.inf, 1e-11])
def test_per_map_spots_equal_one_solve_per_map(film):
    """Groups (asperity spots drawn per realization): each map equals the dense solve of its own spots."""
    rng = np.random.default_rng(8)
    n, n_groups, batch = 9, 3, 7
    base = np.exp(-((np.arange(n) - 4.0)[:, None] ** 2 + (np.arange(n) - 4.0)[None, :] ** 2) / 8.0)
    radius = 2e-6 * base[None, None] * (rng.random((n_groups, 2, n, n)) < 0.6) * np.array([0.5, 1.0])[None, :, None, None]
    masks = rng.random((batch, n, n)) < 0.7
    groups = rng.integers(0, n_groups, batch)
    got = point_model.resistance(masks, _whole(radius), RHO, film_resistance=film,
                                 solver_tolerance=1e-13, groups=groups)
    green = point_model.greenwood_resistance(masks, _whole(radius), RHO, film_resistance=film,
                                             groups=groups)
    for b in range(batch):
        dense, dense_green = point_model.resistance_dense(masks[b : b + 1], radius[groups[b]], PITCH, RHO, film)
        np.testing.assert_allclose(got.resistance[b], dense[0], rtol=1e-9)
        np.testing.assert_allclose(green.resistance[b], dense_green[0], rtol=1e-12)
