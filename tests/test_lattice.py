"""The square lattice constant C of the point model's self term."""

from __future__ import annotations

import math

import pytest
from scipy.special import zeta

from g2tom.physics.lattice import SQUARE_LATTICE_CONSTANT, lattice_constant, square_partial


def _dirichlet_beta_half() -> float:
    """beta(1/2) = sum_k (-1)^k / sqrt(2k + 1) by the Cohen-Villegas-Zagier acceleration (n = 30)."""
    n = 30
    d = (3 + math.sqrt(8)) ** n
    d = (d + 1 / d) / 2
    b, c, s = -1.0, -d, 0.0
    for k in range(n):
        c = b - c
        s += c / math.sqrt(2 * k + 1)
        b = (k + n) * (k - n) * b / ((k + 0.5) * (k + 1))
    return s / d


def test_beta_half_against_a_long_partial_sum():
    """The accelerated series against averaged partial sums (error ~ 1/N^(3/2))."""
    n = 200_000
    partial = sum((-1) ** k / math.sqrt(2 * k + 1) for k in range(n))
    average = partial + 0.5 * (-1) ** n / math.sqrt(2 * n + 1)
    assert _dirichlet_beta_half() == pytest.approx(average, abs=1e-8)


def test_lattice_constant_is_the_continued_epstein_zeta():
    """C = -4 zeta(1/2) beta(1/2), the analytic continuation of the lattice sum of 1/|j|."""
    closed = -4 * zeta(0.5) * _dirichlet_beta_half()
    assert lattice_constant() == pytest.approx(closed, rel=1e-12)
    assert SQUARE_LATTICE_CONSTANT == pytest.approx(lattice_constant(), rel=1e-13)


def test_partial_sums_approach_c_as_one_over_s():
    """The bracket's leading error is -c_1 / s with c_1 = sqrt(2)/6 (the cells' r^-3 / 24 tails)."""
    for n in (20, 40):
        s = n + 0.5
        gap = SQUARE_LATTICE_CONSTANT - square_partial(n)
        assert gap * s == pytest.approx(math.sqrt(2) / 6, rel=2e-3)


def test_lattice_constant_extrapolation_converges():
    """Fewer, smaller squares give the same C to the accuracy their expansion order allows."""
    assert lattice_constant((8, 16, 32)) == pytest.approx(SQUARE_LATTICE_CONSTANT, abs=1e-7)
    assert abs(lattice_constant((32, 64)) - SQUARE_LATTICE_CONSTANT) < 1e-6


@pytest.mark.parametrize("sizes", [(16,), (16, 16)])
def test_lattice_constant_needs_distinct_sizes(sizes):
    with pytest.raises(ValueError, match="at least two distinct"):
        lattice_constant(sizes)


def test_square_partial_needs_a_point():
    with pytest.raises(ValueError, match="n = 0 is out of range"):
        square_partial(0)
