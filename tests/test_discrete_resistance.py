"""The point model's fast paths (one factorization per layout and step, Schur complements,
sets solved alone where that is cheaper) against a direct solve of every set by itself."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import discrete_resistance as dr
from pipeline.physics.discrete_contact import interaction_kernel

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


@pytest.mark.parametrize("nested", [True, False])
@pytest.mark.parametrize("floor", [3e-5, 1e-6])  # 1e-6: close large caps leave some unions indefinite
def test_batched_total_currents_equal_the_direct_solve(nested, floor):
    rng = np.random.default_rng(11 + nested)
    indefinite = 0
    for _ in range(40):
        batch, size, sets = rng.integers(1, 5), rng.integers(1, 40), rng.integers(1, 10)
        kernels, radii = np.zeros((batch, size, size)), np.zeros((batch, sets, size))
        for b in range(batch):
            n = rng.integers(1, size + 1)
            kernels[b, :n, :n], radii[b, :, :n] = layout(rng, n, sets, floor, nested)
            union = kernels[b].copy()
            top = radii[b].max(axis=0)
            union[np.diag_indices(size)] = np.where(top > 0, 1.0 / (2.0 * np.where(top > 0, top, 1.0)), 1.0)
            indefinite += np.linalg.eigvalsh(union).min() <= 0
        got = dr.total_currents(kernels, radii)
        want = np.array([direct(k, r) for k, r in zip(kernels, radii)])
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=0.0)
    if floor < 1e-5:
        assert indefinite > 0  # the LU path was exercised


def test_wide_partial_sets_take_the_whole_path_with_the_same_answer(monkeypatch):
    rng = np.random.default_rng(3)
    kernel, radii = layout(rng, 30, 9, 3e-5, nested=False)
    radii = radii * rng.uniform(0.5, 0.99, radii.shape)  # every spot below its largest radius somewhere
    calls = []
    whole = dr._whole_sets
    monkeypatch.setattr(dr, "_whole_sets", lambda k, a: calls.append(a.shape) or whole(k, a))
    np.testing.assert_allclose(dr.total_currents(kernel[None], radii[None])[0], direct(kernel, radii), rtol=1e-10)
    assert calls  # the flop rule chose LU


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


def test_answer_does_not_depend_on_the_order_of_the_spots():
    rng = np.random.default_rng(8)
    kernel, radii = layout(rng, 40, 9, 3e-5, nested=True)
    turn = rng.permutation(40)
    np.testing.assert_allclose(dr.total_currents(kernel[None], radii[None]),
                               dr.total_currents(kernel[np.ix_(turn, turn)][None], radii[None][..., turn]),
                               rtol=1e-12)


def test_many_layouts_solved_together_equal_each_alone_bitwise():
    """A layout's answer does not depend on the other layouts of the call (the cube's chunking)."""
    rng = np.random.default_rng(21)
    kernels, radii = [], []
    for n in (3, 17, 40, 70):
        kernel, a = layout(rng, n, 9 * 5, 3e-5, nested=True)
        a = a.reshape(9, 5, n)
        a[:, 0] = 0.0  # a step where no spot conducts
        kernels.append(kernel)
        radii.append(a)
    together = dr.layout_resistances(kernels, radii, RHO)
    for kernel, a, got in zip(kernels, radii, together):
        alone = dr.layout_resistances([kernel], [a], RHO)[0]
        np.testing.assert_array_equal(got, alone)
        assert np.all(np.isinf(got[:, 0]))
        with np.errstate(divide="ignore"):
            for step in range(1, 5):
                np.testing.assert_allclose(got[:, step], RHO / direct(kernel, a[:, step]), rtol=1e-10)


def test_bucket_pads_by_at_most_an_eighth():
    size = np.arange(0, 600)
    padded = dr.bucket(size)
    assert np.all(padded >= size) and np.all(padded[:17] == size[:17])
    assert np.all(padded <= np.ceil(size * 1.125))
    assert np.all(np.diff(padded) >= 0)
