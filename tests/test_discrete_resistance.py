"""The point model's fast paths (one factorization per layout and step, Schur complements,
sets solved alone where that is cheaper) against a direct solve of every set by itself."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.physics import discrete_resistance as dr
from g2tom.physics.discrete_contact import interaction_kernel

RHO = 7.2e-7


def direct(kernel: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """``1^T M^-1 1`` of every set (row of ``radii``) on its conducting spots, by LU: the oracle."""
    out = []
    for row in radii:
        spots = np.flatnonzero(row > 0)
        matrix = kernel[np.ix_(spots, spots)].copy()
        matrix[np.diag_indices_from(matrix)] = 1.0 / (2.0 * row[spots])
        out.append(np.linalg.solve(matrix, np.ones(spots.size)).sum() if spots.size else 0.0)
    return np.array(out)


def layout(rng: np.random.Generator, n: int, sets: int, floor: float, nested: bool):
    """Spots on a 1 mm square, radii 1-20 um, clean shares with whole, partial and no cover."""
    x, y = rng.uniform(0.0, 1e-3, (2, n))
    share = rng.uniform(0.0, 1.0, (sets, n))
    share[share > 0.6], share[share < 0.15] = 1.0, 0.0
    if nested:  # as the oxide fractions of one field: cover grows from set to set
        share = np.sort(share, axis=0)[::-1]
    return interaction_kernel(x, y, floor), rng.uniform(1e-6, 2e-5, n) * np.sqrt(share)


def solved(kernel: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, int]:
    """The compiled solve of one step's sets (rows of ``radii``) and the path it took."""
    total, path = dr.currents(kernel, radii[:, None, :])
    return total[:, 0], int(path[0])


@pytest.mark.parametrize("nested", [True, False])
@pytest.mark.parametrize("floor", [3e-5, 1e-6])  # 1e-6: close large caps leave some unions indefinite
def test_every_path_equals_the_direct_solve(nested, floor):
    rng = np.random.default_rng(11 + nested)
    paths = set()
    for _ in range(60):
        n, sets = rng.integers(1, 40), rng.integers(1, 10)
        kernel, radii = layout(rng, n, sets, floor, nested)
        got, path = solved(kernel, radii)
        paths.add(path)
        np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-10, atol=0.0)
    if floor < 1e-5:
        assert dr.INDEFINITE in paths  # sets solved alone (here: wide partial sets) on an indefinite union
    assert dr.NESTED in paths


def test_an_indefinite_union_shares_its_signed_factor():
    """Large caps crowded closer than their radii (flattened capped caps): the union is indefinite,
    its nested sets still share one (signed) factorization, with the direct answer."""
    rng = np.random.default_rng(23)
    for _ in range(20):
        n, sets = rng.integers(20, 90), rng.integers(2, 10)
        x, y = rng.uniform(0.0, 2e-4, (2, n))
        kernel = interaction_kernel(x, y, 1e-6)
        top = rng.uniform(1e-5, 2e-5, n)
        cover = np.sort(rng.uniform(size=(sets, n)) < np.linspace(0.9, 0.2, sets)[:, None], axis=0)[::-1]
        radii = top * cover
        radii[0] = top  # every spot conducts in the first set
        union = kernel.copy()
        union[np.diag_indices(n)] = 0.5 / top
        assert np.linalg.eigvalsh(union)[0] < 0
        got, path = solved(kernel, radii)
        assert path == dr.SIGNED
        np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-10, atol=0.0)


def test_a_pivot_near_zero_leaves_the_signed_factor_for_lu():
    """Two caps closer than the floor, sized so that the union's second pivot is -1e-5 of its
    diagonal: the signed factor gives up (it would amplify rounding) and every set is solved
    alone with the direct answer; a little further from singular, the signed path answers."""
    floor = 1e-6
    coupling = 1.0 / (np.pi * floor)
    kernel = np.array([[0.0, coupling], [coupling, 0.0]])
    for margin, path_wanted in ((1e-5, dr.INDEFINITE), (0.5, dr.SIGNED)):
        radius = np.sqrt(1.0 + margin) / (2.0 * coupling)  # second pivot 1/(2a) (1 - (2a k)^2) = -margin / (2a)
        radii = np.array([[radius, radius], [radius, 0.7 * radius], [radius, radius]])
        got, path = solved(kernel, radii)
        assert path == path_wanted
        np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-9)


def test_wide_partial_sets_are_solved_alone_with_the_same_answer():
    rng = np.random.default_rng(3)
    kernel, radii = layout(rng, 30, 9, 3e-5, nested=False)
    radii = radii * rng.uniform(0.5, 0.99, radii.shape)  # every spot below its largest radius somewhere
    got, path = solved(kernel, radii)
    assert path == dr.WHOLE  # the flop rule chose one factorization per set
    np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-10)


def test_nested_sets_share_one_factorization_with_the_same_answer():
    rng = np.random.default_rng(4)
    kernel, radii = layout(rng, 60, 9, 3e-5, nested=True)
    radii = radii.max(axis=0) * (np.sort(rng.uniform(size=(9, 60)), axis=0) > 0.4)  # whole spots, nested
    radii[:, :3] *= 0.7 ** np.arange(9)[:, None]  # and three partial ones
    got, path = solved(kernel, radii)
    assert path == dr.NESTED
    np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-10)


def test_a_set_with_no_spot_and_no_step_conducting():
    rng = np.random.default_rng(9)
    kernel, radii = layout(rng, 12, 3, 3e-5, nested=True)
    radii[1] = 0.0
    got, path = solved(kernel, radii)
    assert got[1] == 0.0 and path in (dr.NESTED, dr.WHOLE)
    total, paths = dr.currents(kernel, np.zeros((3, 2, 12)))
    assert np.all(total == 0.0) and np.all(paths == dr.NONE)


def test_one_spot_is_a_disc():
    kernel = np.zeros((1, 1))
    np.testing.assert_allclose(dr.resistances(kernel, np.array([[2e-6]]), RHO), [RHO / (2 * 2e-6)], rtol=1e-14)


def test_resistances_solve_each_step_and_its_sets_exactly():
    rng = np.random.default_rng(5)
    kernel, a = layout(rng, 25, 9 * 4, 3e-5, nested=True)
    a = a.reshape(9, 4, 25)
    a[:, 2] = 0.0  # a step where no spot conducts: open circuits
    got = dr.resistances(kernel, a, RHO)
    assert got.shape == (9, 4)
    for step in (0, 1, 3):
        with np.errstate(divide="ignore"):  # a set with no conducting spot: inf both ways
            np.testing.assert_allclose(got[:, step], RHO / direct(kernel, a[:, step]), rtol=1e-10)
    assert np.all(np.isinf(got[:, 2]))


def test_greenwood_form_is_the_rayleigh_quotient_and_bounds_the_point_model():
    rng = np.random.default_rng(6)
    kernel, a = layout(rng, 30, 5, 3e-5, nested=True)
    greenwood = dr.resistances(kernel, a, RHO, "greenwood")
    point = dr.resistances(kernel, a, RHO, "point")
    for row, r_g in zip(a, greenwood):
        if row.sum() == 0:
            assert np.isinf(r_g)
            continue
        matrix = kernel + np.diag(np.where(row > 0, 1.0 / (2.0 * np.where(row > 0, row, 1.0)), 0.0))
        np.testing.assert_allclose(r_g, RHO * (row @ matrix @ row) / row.sum() ** 2, rtol=1e-12)
    assert np.all(greenwood >= point * (1 - 1e-12))


def test_answer_does_not_depend_on_the_order_of_the_spots():
    rng = np.random.default_rng(8)
    kernel, radii = layout(rng, 40, 9, 3e-5, nested=True)
    turn = rng.permutation(40)
    np.testing.assert_allclose(solved(kernel, radii)[0], solved(kernel[np.ix_(turn, turn)], radii[:, turn])[0],
                               rtol=1e-12)


def test_bad_shapes_and_models_are_refused():
    with pytest.raises(ValueError, match="model"):
        dr.resistances(np.zeros((2, 2)), np.ones(2), RHO, "exact")
    with pytest.raises(ValueError, match="must be"):
        dr.currents(np.zeros((2, 2)), np.ones((1, 1, 3)))


@pytest.mark.parametrize("nested", [True, False])
def test_large_sets_factorized_by_lapack_equal_the_direct_solve(nested):
    assert dr.LAPACK_FROM < 150
    rng = np.random.default_rng(13)
    kernel, radii = layout(rng, 150, 4, 3e-5, nested)
    if nested:  # whole spots: one union factorization of 150 + 1
        radii = radii.max(axis=0) * (np.sort(rng.uniform(size=radii.shape), axis=0) > 0.3)
    got, path = solved(kernel, radii)
    np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-10)
    assert path == (dr.NESTED if nested else dr.WHOLE)


@pytest.mark.parametrize("nested", [True, False])
def test_conjugate_gradients_equal_the_direct_solve(nested):
    """Forced onto every union (``iterative_from=1``), conjugate gradients give every set's
    ``1^T M^-1 1`` within 1e-9 of LU; where the union is indefinite they give up and the step is
    factorized, with the direct answer."""
    rng = np.random.default_rng(17 + nested)
    paths = set()
    for floor in (3e-5, 1e-6):
        for _ in range(40):
            n, sets = rng.integers(1, 60), rng.integers(1, 8)
            kernel, radii = layout(rng, n, sets, floor, nested)
            total, path = dr.currents(kernel, radii[:, None, :], iterative_from=1)
            paths.add(int(path[0]))
            np.testing.assert_allclose(total[:, 0], direct(kernel, radii), rtol=1e-9, atol=0.0)
    assert dr.ITERATIVE in paths and dr.INDEFINITE in paths


def test_large_unions_take_conjugate_gradients_by_default():
    rng = np.random.default_rng(19)
    n = dr.ITERATIVE_FROM + 50
    kernel, radii = layout(rng, n, 3, 3e-5, True)
    radii[0] = np.where(radii[0] > 0, radii[0], 1e-6)  # every spot conducts in the first set
    got, path = solved(kernel, radii)
    assert path == dr.ITERATIVE
    np.testing.assert_allclose(got, direct(kernel, radii), rtol=1e-9)
    below, path_below = dr.currents(kernel, radii[:, None, :], iterative_from=n + 1)
    assert int(path_below[0]) != dr.ITERATIVE
    np.testing.assert_allclose(got, below[:, 0], rtol=1e-9)


def test_bench_of_large_unions_compares_both_paths_on_a_solved_surface(monkeypatch):
    """The bench's large unions on a small scene (mu 7, Pi 40: unions of ~100-250 spots): both
    paths timed on the same sets of a solved surface, equal within 1e-9."""
    from g2tom.bench import discrete as bench_discrete
    from g2tom.before_work import load_scenario

    monkeypatch.setattr(bench_discrete, "LARGE_SCENE", (7.0, 40.0))
    monkeypatch.setattr(bench_discrete, "LARGE_UNIONS", (100, 200))
    monkeypatch.setattr(bench_discrete, "LARGE_REPEATS", 1)
    scenario = load_scenario("paper", {"oxide.xi": [0.3, 0.7], "oxide.lambda": [1.0, 23.0], "loading.n_delta": 8})
    rows = bench_discrete._large_unions(scenario)
    assert [(r["lambda"], r["sets"]) for r in rows] == [(1.0, 2), (1.0, 2), (23.0, 2), (23.0, 2)]
    assert all(r["iterative_path"] for r in rows)
    assert max(r["max_relative_difference"] for r in rows) < 1e-9
    assert all(r["union"] > 50 and r["ratio_factorized_to_iterative"] > 0 for r in rows)
