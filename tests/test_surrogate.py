"""The truncated-SVD polynomial surrogate (Eq. 26) and the surrogate stage."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config import ConfigError
from pipeline.physics import surrogate as sg
from pipeline.stages import fits, surrogate
from tests.test_fits_stage import assert_labelled, synthetic_cube, true_alpha

LAM = np.array([1.0, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23])
XI = np.linspace(0.1, 0.9, 9)


def separable_rank2(lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Rank-2 field with cubic/quadratic modes in w and z (the paper's alpha orders)."""
    w, z = np.log(lam)[:, None], -np.log1p(-xi)[None, :]
    return (1 + 0.2 * w - 0.05 * w**3) * (0.5 + z**2) + (0.3 - 0.1 * w**2) * (z - 0.2 * z**2)


def test_reproduces_separable_rank2_field_exactly() -> None:
    matrix = separable_rank2(LAM, XI)
    model = sg.fit_surrogate(matrix, LAM, XI, rank=2, order_w=3, order_z=2)
    np.testing.assert_allclose(model(LAM[:, None], XI[None, :]), matrix, rtol=1e-10)
    # ...and between grid points, since the modes are exact polynomials
    np.testing.assert_allclose(model(4.0, 0.45), separable_rank2(np.array([4.0]), np.array([0.45]))[0, 0], rtol=1e-9)
    assert model.coef_w.shape == (2, 4) and model.coef_z.shape == (2, 3)
    assert model.singular_values[2] < 1e-12 * model.singular_values[0]


def test_rank_one_is_not_enough_for_rank_two() -> None:
    matrix = separable_rank2(LAM, XI)
    model = sg.fit_surrogate(matrix, LAM, XI, rank=1, order_w=3, order_z=2)
    assert np.max(np.abs(model(LAM[:, None], XI[None, :]) / matrix - 1)) > 1e-3


def test_loo_prefers_sufficient_orders() -> None:
    matrix = separable_rank2(LAM, XI)
    assert sg.loo_error(matrix, LAM, XI, 2, 3, 2) < 1e-9
    scan = sg.order_scan(matrix, LAM, XI, 2, 4, 3)
    assert scan[3, 2] < 1e-9 and scan[1, 1] > 1e-3
    assert np.isnan(sg.loo_error(matrix[:3, :3], LAM[:3], XI[:3], 2, 2, 1))


def test_loo_matches_explicit_refits() -> None:
    # Each line is predicted by a surrogate fitted on the grid without it: never by one
    # that has seen it (which would report the in-sample error instead).
    matrix = separable_rank2(LAM, XI) * np.exp(0.05 * np.random.default_rng(4).standard_normal((LAM.size, XI.size)))
    rank, ow, oz = 2, 2, 1
    rel = []
    for i in range(LAM.size):
        keep = np.arange(LAM.size) != i
        model = sg.fit_surrogate(matrix[keep], LAM[keep], XI, rank, ow, oz)
        rel.append(model(LAM[i], XI) / matrix[i] - 1)
    for j in range(XI.size):
        keep = np.arange(XI.size) != j
        model = sg.fit_surrogate(matrix[:, keep], LAM, XI[keep], rank, ow, oz)
        rel.append(model(LAM, XI[j]) / matrix[:, j] - 1)
    expected = np.sqrt(np.mean(np.concatenate(rel) ** 2))
    assert sg.loo_error(matrix, LAM, XI, rank, ow, oz) == pytest.approx(expected, rel=1e-9)
    in_sample = sg.fit_surrogate(matrix, LAM, XI, rank, ow, oz)(LAM[:, None], XI[None, :]) / matrix - 1
    assert expected > np.sqrt(np.mean(in_sample**2))


def test_bad_input() -> None:
    matrix = separable_rank2(LAM, XI)
    with pytest.raises(ValueError, match="orders"):
        sg.fit_surrogate(matrix[:3], LAM[:3], XI, 2, 3, 2)
    bad = matrix.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        sg.fit_surrogate(bad, LAM, XI, 2, 3, 2)


def test_stage_builds_table3_and_cv(tmp_path, small) -> None:
    with pytest.warns(UserWarning, match="reduced to"):
        ds = surrogate.build(small, fits.build(small, synthetic_cube(small, noise=0.0)))
    lam, xi = np.asarray(small.oxide.lambda_), np.asarray(small.oxide.xi)
    # small grid (3 x 3): orders are reduced to 2 in w, and alpha is quadratic there
    np.testing.assert_allclose(ds["alpha_fit"], true_alpha(lam, xi), rtol=1e-9)
    rows = surrogate.table3_rows(ds)
    assert len(rows) == 9 and {"alpha_error_percent", "gamma_surrogate"} <= set(rows[0])
    md = surrogate.table3_markdown(ds)
    assert md.count("\n") == 11 and "alpha fit" in md
    assert surrogate.table3_csv(ds).splitlines()[0].startswith("xi,lambda,alpha_fit")
    # the reduced orders (w 2) cannot be cross-validated on 3 lambdas: say so, not "best (nan)"
    assert "cannot be cross-validated" in ds["alpha_loo"].attrs["verdict"]
    assert "nan" not in ds["alpha_loo"].attrs["verdict"]
    for name in ("band_ratio_lower", "band_ratio_upper", "open_probability"):
        assert ds[name].dims == ("lambda", "xi", "step")
    assert float(ds["force_normalized_range"][0]) > 0
    assert_labelled(ds)


def test_stage_rejects_unfitted_cells(small) -> None:
    cube = synthetic_cube(small, noise=0.0)
    cube["resistance"][0, 0] = np.inf
    with pytest.raises(ConfigError, match="alpha could not be fitted"):
        surrogate.build(small, fits.build(small, cube))
