"""The benchmarks' timer: the median of repeated calls, each without the influence matrices an
earlier solve kept (what one stage call pays)."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.bench.timing import median_time
from g2tom.physics import radial_grid


def test_each_timed_call_builds_its_own_influence_matrix() -> None:
    nodes = radial_grid.radial_nodes(64, 1e-3)
    kept_before_each_call = []

    def solve() -> np.ndarray:
        kept_before_each_call.append(radial_grid._kept_matrix.cache_info().currsize)
        return radial_grid.influence_matrix(nodes, 1e11)

    radial_grid.influence_matrix(nodes, 1e11)  # kept by an earlier solve
    seconds, matrix = median_time(solve, 3)
    assert kept_before_each_call == [0, 0, 0] and seconds > 0
    np.testing.assert_array_equal(matrix, radial_grid.influence_matrix(nodes, 1e11))


def test_the_median_of_the_calls_and_the_last_result() -> None:
    calls = iter(range(5))
    seconds, last = median_time(lambda: next(calls), 5)
    assert last == 4 and seconds >= 0
    with pytest.raises(ValueError, match="repeats = 0 is out of range"):
        median_time(lambda: None, 0)
