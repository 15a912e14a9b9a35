"""The truncated-SVD polynomial surrogate (Eq. 26) and the surrogate stage."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import polynomial as P
from scipy.optimize import least_squares

from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.fitting import surrogate as sg
from g2tom.fitting import surrogate_joint as sg_joint
from g2tom.fitting import surrogate_paper as sg_paper
from g2tom.stages import fits, surrogate, table3
from tests.conftest import SMALL_OVERRIDES
from tests.test_fits_stage import assert_labelled, synthetic_cube, true_alpha

LAM = np.array([1.0, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23])
XI = np.linspace(0.1, 0.9, 9)


def separable_rank2(lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Rank-2 field with cubic/quadratic modes in w and z (the paper's alpha orders)."""
    w, z = np.log(lam)[:, None], -np.log1p(-xi)[None, :]
    return (1 + 0.2 * w - 0.05 * w**3) * (0.5 + z**2) + (0.3 - 0.1 * w**2) * (z - 0.2 * z**2)


def test_reproduces_separable_rank2_field_exactly() -> None:
    matrix = separable_rank2(LAM, XI)
    model = sg_paper.fit_surrogate(matrix, LAM, XI, rank=2, order_w=3, order_z=2)
    np.testing.assert_allclose(model(LAM[:, None], XI[None, :]), matrix, rtol=1e-10)
    # ...and between grid points, since the modes are exact polynomials
    np.testing.assert_allclose(model(4.0, 0.45), separable_rank2(np.array([4.0]), np.array([0.45]))[0, 0], rtol=1e-9)
    assert model.coef_w.shape == (2, 4) and model.coef_z.shape == (2, 3)
    assert model.singular_values[2] < 1e-12 * model.singular_values[0]


def test_rank_one_is_not_enough_for_rank_two() -> None:
    matrix = separable_rank2(LAM, XI)
    model = sg_paper.fit_surrogate(matrix, LAM, XI, rank=1, order_w=3, order_z=2)
    assert np.max(np.abs(model(LAM[:, None], XI[None, :]) / matrix - 1)) > 1e-3


def test_loo_prefers_sufficient_orders() -> None:
    matrix = separable_rank2(LAM, XI)
    assert sg_paper.loo_error(matrix, LAM, XI, 2, 3, 2) < 1e-9
    scan = sg_paper.order_scan(matrix, LAM, XI, 2, 4, 3)
    assert scan[3, 2] < 1e-9 and scan[1, 1] > 1e-3
    assert np.isnan(sg_paper.loo_error(matrix[:3, :3], LAM[:3], XI[:3], 2, 2, 1))


def test_loo_matches_explicit_refits() -> None:
    # Each line is predicted by a surrogate fitted on the grid without it: never by one
    # that has seen it (which would report the in-sample error instead).
    matrix = separable_rank2(LAM, XI) * np.exp(0.05 * np.random.default_rng(4).standard_normal((LAM.size, XI.size)))
    rank, ow, oz = 2, 2, 1
    rel = []
    for i in range(LAM.size):
        keep = np.arange(LAM.size) != i
        model = sg_paper.fit_surrogate(matrix[keep], LAM[keep], XI, rank, ow, oz)
        rel.append(model(LAM[i], XI) / matrix[i] - 1)
    for j in range(XI.size):
        keep = np.arange(XI.size) != j
        model = sg_paper.fit_surrogate(matrix[:, keep], LAM, XI[keep], rank, ow, oz)
        rel.append(model(LAM, XI[j]) / matrix[:, j] - 1)
    expected = np.sqrt(np.mean(np.concatenate(rel) ** 2))
    assert sg_paper.loo_error(matrix, LAM, XI, rank, ow, oz) == pytest.approx(expected, rel=1e-9)
    in_sample = sg_paper.fit_surrogate(matrix, LAM, XI, rank, ow, oz)(LAM[:, None], XI[None, :]) / matrix - 1
    assert expected > np.sqrt(np.mean(in_sample**2))


def test_bad_input() -> None:
    matrix = separable_rank2(LAM, XI)
    with pytest.raises(ValueError, match="orders"):
        sg_paper.fit_surrogate(matrix[:3], LAM[:3], XI, 2, 3, 2)
    bad = matrix.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        sg_paper.fit_surrogate(bad, LAM, XI, 2, 3, 2)


def test_paper_stage_builds_table3_and_cv(tmp_path, small) -> None:
    paper_method = load_scenario("paper_gt", {**SMALL_OVERRIDES, "surrogate.method": "paper"})
    with pytest.warns(UserWarning, match="reduced to"):
        ds = surrogate.build(paper_method, fits.build(paper_method, synthetic_cube(paper_method, noise=0.0)))
    lam, xi = np.asarray(small.oxide.lambda_), np.asarray(small.oxide.xi)
    # small grid (3 x 3): orders are reduced to 2 in w, and alpha is quadratic there
    np.testing.assert_allclose(ds["alpha_fit"], true_alpha(lam, xi), rtol=1e-9)
    rows = table3.table3_rows(ds)
    assert len(rows) == 9 and {"alpha_error_percent", "gamma_surrogate"} <= set(rows[0])
    md = table3.table3_markdown(ds)
    assert md.count("\n") == 11 and "alpha fit" in md
    assert table3.table3_csv(ds).splitlines()[0].startswith("xi,lambda,alpha_fit")
    # the reduced orders (w 2) cannot be cross-validated on 3 lambdas: say so, not "best (nan)"
    assert "cannot be cross-validated" in ds["alpha_loo"].attrs["verdict"]
    assert "nan" not in ds["alpha_loo"].attrs["verdict"]
    for name in ("band_ratio_lower", "band_ratio_upper", "open_probability"):
        assert ds[name].dims == ("lambda", "xi", "step")
    assert float(ds["force_normalized_range"][0]) > 0
    assert ds.attrs["alpha_transform"] == "identity" and ds.attrs["method"] == "paper"
    assert_labelled(ds)


def test_published_surrogate_numbers_unchanged_by_the_joint_method() -> None:
    """The paper method's coefficients are the plain SVD-then-polyfit of Sect. 3.1, bit for bit."""
    matrix = separable_rank2(LAM, XI) * np.exp(0.05 * np.random.default_rng(2).standard_normal((LAM.size, XI.size)))
    model = sg_paper.fit_surrogate(matrix, LAM, XI, 2, 3, 2)
    U, s, Vt = np.linalg.svd(matrix, full_matrices=False)
    u, v = U[:, :2] * np.sqrt(s[:2]), Vt[:2].T * np.sqrt(s[:2])
    flip = np.where(v.sum(axis=0) < 0, -1.0, 1.0)
    w, z = np.log(LAM), -np.log1p(-XI)
    for k in range(2):
        np.testing.assert_array_equal(model.coef_w[k], P.polyfit(w, u[:, k] * flip[k], 3))
        np.testing.assert_array_equal(model.coef_z[k], P.polyfit(z, v[:, k] * flip[k], 2))
    assert load_scenario("published").surrogate.method == "paper"


def test_joint_stage_on_small_grid(small) -> None:
    with pytest.warns(UserWarning, match=r"surrogate for alpha: rank/orders scanned up to .* reduced to"):
        ds = surrogate.build(small, fits.build(small, synthetic_cube(small, noise=0.0)))
    # 3 x 3 grid: orders <= 1 can be cross-validated; the chosen model is reported with its size
    for p in ("alpha", "gamma"):
        assert ds.attrs[f"{p}_order_w"] <= 1 and ds.attrs[f"{p}_order_z"] <= 1
        assert ds.attrs[f"{p}_free_parameters"] == sg_joint.free_parameters(ds.attrs[f"{p}_rank"], ds.attrs[f"{p}_order_w"], ds.attrs[f"{p}_order_z"])
        assert np.isfinite(ds[f"{p}_cv_error"]).all() and np.isfinite(ds.attrs[f"{p}_cv_rms"])
        assert ds[f"{p}_cv_rms"].dims == (f"{p}_candidate",)
        # the candidate chosen scores what the attribute says
        chosen = (ds[f"{p}_cv_rank"] == ds.attrs[f"{p}_rank"]) & (ds[f"{p}_cv_order_w"] == ds.attrs[f"{p}_order_w"]) & (
            ds[f"{p}_cv_order_z"] == ds.attrs[f"{p}_order_z"]) & (ds[f"{p}_cv_transform"] == ds.attrs[f"{p}_transform"])
        assert float(ds[f"{p}_cv_rms"][chosen.values][0]) == pytest.approx(ds.attrs[f"{p}_cv_rms"])
    assert ds.attrs["alpha_transform"] == "log"
    assert_labelled(ds)


# ------------------------------------------------------------------ joint fit
def log_rank2(lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """exp of a rank-2 field with orders (3, 2), spanning roughly 0.2 ... 5 like alpha."""
    w, z = np.log(lam)[:, None], -np.log1p(-xi)[None, :]
    return np.exp((-1.2 + 0.05 * w - 0.01 * w**3) * (1.0 - 0.3 * z) + (0.1 * w - 0.03 * w**2) * (0.2 + 0.5 * z + 0.3 * z**2))


def test_free_parameters() -> None:
    assert sg_joint.free_parameters(2, 3, 2) == 10  # not the paper's 2 (4 + 3) = 14
    assert sg_joint.free_parameters(2, 2, 1) == 6  # = the full 3 x 2 tensor polynomial
    assert sg_joint.free_parameters(3, 2, 1) == 6
    assert sg_joint.free_parameters(1, 0, 0) == 1


def test_joint_recovers_separable_rank2_in_log_exactly() -> None:
    field = log_rank2(LAM, XI)
    sigma = np.random.default_rng(3).uniform(0.005, 0.2, field.shape)  # unequal weights: the ALS path
    model = sg_joint.fit_joint(field, LAM, XI, 2, 3, 2, "log", sigma)
    assert model.iterations > 0
    np.testing.assert_allclose(model(LAM[:, None], XI[None, :]), field, rtol=1e-9)
    np.testing.assert_allclose(model(4.0, 0.45), log_rank2(np.array([4.0]), np.array([0.45]))[0, 0], rtol=1e-9)
    assert model.coef_w.shape == (2, 4) and model.coef_z.shape == (2, 3)
    # the closed formula is the model
    formula = sg.closed_formula(model.coef_w, model.coef_z, "log", "alpha").split("=", 1)[1]
    value = eval(formula.replace("EXP", "np.exp").replace("^", "**"), {"np": np, "w": np.log(4.0), "z": -np.log1p(-0.45)})
    assert value == pytest.approx(float(model(4.0, 0.45)), rel=1e-12)


def test_joint_fit_reaches_the_weighted_optimum() -> None:
    """ALS ends where a general nonlinear least-squares solver ends, from any start."""
    rng = np.random.default_rng(5)
    field = log_rank2(LAM, XI) * np.exp(0.05 * rng.standard_normal((LAM.size, XI.size)))
    sigma = rng.uniform(0.01, 0.1, field.shape)
    model = sg_joint.fit_joint(field, LAM, XI, 2, 3, 2, "log", sigma)
    A, B = np.vander(np.log(LAM), 4, increasing=True), np.vander(-np.log1p(-XI), 3, increasing=True)
    t = np.log(field)

    def residual(x: np.ndarray) -> np.ndarray:
        X, Y = x[:8].reshape(4, 2), x[8:].reshape(3, 2)
        return ((t - A @ X @ Y.T @ B.T) / sigma).ravel()

    als = np.sum(((t - np.log(model(LAM[:, None], XI[None, :]))) / sigma) ** 2)
    general = min(np.sum(least_squares(residual, rng.standard_normal(14), method="lm", xtol=1e-15, ftol=1e-15).fun ** 2)
                  for _ in range(5))
    assert als <= general * (1 + 1e-8)
    # ...and it is a better weighted fit than the paper's SVD-then-polyfit of the same orders
    paper = sg_paper.fit_surrogate(field, LAM, XI, 2, 3, 2)(LAM[:, None], XI[None, :])
    assert als < np.sum(((t - np.log(paper)) / sigma) ** 2)


def smooth_field(lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """A smooth alpha-like field outside the model class: steep in xi, mild in lambda."""
    w, z = np.log(lam)[:, None], -np.log1p(-xi)[None, :]
    return 0.24 * np.exp(0.35 * z**1.6 * (1 + 0.15 * w) + 0.02 * np.sin(w))


def test_grid_error_bounded_on_smooth_noisy_field() -> None:
    rng = np.random.default_rng(11)
    truth = smooth_field(LAM, XI)
    half = 0.004 + 0.02 * (XI[None, :] ** 2) * np.ones((LAM.size, 1))  # relative 95 % half-widths, larger at high xi
    data = truth * np.exp(half / 1.96 * rng.standard_normal(truth.shape))
    sigma = np.fmax(half, 0.01)
    best, _ = sg_joint.select_model(data, LAM, XI, ("log",), 3, 4, 3, {"log": sigma}, 0.05)
    model = sg_joint.fit_joint(data, LAM, XI, best.rank, best.order_w, best.order_z, "log", sigma)
    error = np.abs(model(LAM[:, None], XI[None, :]) / data - 1)
    assert np.all(error <= np.fmax(0.03, half)), error.max()
    assert best.score <= 0.05
    # the paper's method with its orders misses the same field by more
    paper = sg_paper.fit_surrogate(data, LAM, XI, 2, 3, 2)(LAM[:, None], XI[None, :])
    assert np.abs(paper / data - 1).max() > error.max()


@pytest.mark.parametrize("rank, order_w, order_z", [(2, 3, 2), (1, 2, 1), (2, 1, 2)])
def test_cross_validation_picks_the_true_orders(rank: int, order_w: int, order_z: int) -> None:
    rng = np.random.default_rng(rank * 10 + order_w)
    w, z = np.log(LAM)[:, None], -np.log1p(-XI)[None, :]
    coef_w = rng.uniform(-1, 1, (rank, order_w + 1))
    coef_z = rng.uniform(-1, 1, (rank, order_z + 1))
    log_field = sum(P.polyval(w, cw) * P.polyval(z, cz) for cw, cz in zip(coef_w, coef_z))
    field = np.exp(log_field + 0.002 * rng.standard_normal(log_field.shape))
    best, tried = sg_joint.select_model(field, LAM, XI, ("log",), 3, 4, 3, None, 0.05)
    assert (best.rank, best.order_w, best.order_z) == (rank, order_w, order_z)
    assert len(tried) > 20 and best.score < 0.01


def test_cross_validate_matches_explicit_refits() -> None:
    field = log_rank2(LAM, XI) * np.exp(0.05 * np.random.default_rng(4).standard_normal((LAM.size, XI.size)))
    sigma = np.full(field.shape, 0.02)
    sigma[:, -1] = 0.1
    pred = sg_joint.cross_validate(field, LAM, XI, 2, 2, 1, "log", sigma)
    keep = np.arange(LAM.size) != 5
    row = sg_joint.fit_joint(field[keep], LAM[keep], XI, 2, 2, 1, "log", sigma[keep])(LAM[5], XI)
    np.testing.assert_allclose(pred[0, 5], row, rtol=1e-12)
    keep = np.arange(XI.size) != 8
    col = sg_joint.fit_joint(field[:, keep], LAM, XI[keep], 2, 2, 1, "log", sigma[:, keep])(LAM, XI[8])
    np.testing.assert_allclose(pred[1, :, 8], col, rtol=1e-12)
    assert sg_joint.cross_validate(field[:3], LAM[:3], XI, 1, 2, 1) is None


def test_joint_bad_input() -> None:
    field = log_rank2(LAM, XI)
    with pytest.raises(ValueError, match="orders"):
        sg_joint.fit_joint(field[:3], LAM[:3], XI, 2, 3, 2)
    with pytest.raises(ValueError, match="positive"):
        sg_joint.fit_joint(-field, LAM, XI, 2, 3, 2, "log")
    with pytest.raises(ValueError, match="sigma"):
        sg_joint.fit_joint(field, LAM, XI, 2, 3, 2, "log", np.zeros_like(field))


def test_stage_rejects_unfitted_cells(small) -> None:
    cube = synthetic_cube(small, noise=0.0)
    cube["resistance"][0, 0] = np.inf
    with pytest.raises(ConfigError, match="alpha could not be fitted"):
        surrogate.build(small, fits.build(small, cube))


def test_cross_validation_picks_the_better_transform() -> None:
    w, z = np.log(LAM)[:, None], -np.log1p(-XI)[None, :]
    linear = 0.23 + 0.1 * z + 0.02 * w * z  # exact in gamma itself, rank 2, orders (1, 1)
    best, _ = sg_joint.select_model(linear, LAM, XI, sg.TRANSFORMS, 3, 4, 3, None, 0.05)
    assert (best.transform, best.order_w, best.order_z) == ("identity", 1, 1) and best.score < 1e-10
    best, _ = sg_joint.select_model(np.exp(linear), LAM, XI, sg.TRANSFORMS, 3, 4, 3, None, 0.05)
    assert (best.transform, best.order_w, best.order_z) == ("log", 1, 1) and best.score < 1e-10


def test_weights_keep_an_uncertain_cell_from_pulling_the_fit() -> None:
    field = log_rank2(LAM, XI)
    data = field.copy()
    data[-1, -1] *= 1.5  # one cell off by 50 %, with a wide interval
    sigma = np.full(field.shape, 0.01)
    sigma[-1, -1] = 10.0
    rest = np.ones(field.shape, dtype=bool)
    rest[-1, -1] = False
    weighted = sg_joint.fit_joint(data, LAM, XI, 2, 3, 2, "log", sigma)(LAM[:, None], XI[None, :])
    plain = sg_joint.fit_joint(data, LAM, XI, 2, 3, 2, "log")(LAM[:, None], XI[None, :])
    assert np.abs(weighted / field - 1)[rest].max() < 1e-4
    assert np.abs(plain / field - 1)[rest].max() > 1e-2


def test_lambda_map_specs_round_trip_and_reject_malformed() -> None:
    assert sg.split_spec("log") == ("log", "log") and sg.model_spec("log", "log") == "log"
    for t in sg.TRANSFORMS:
        for m in sg.W_MAPS:
            assert sg.split_spec(sg.model_spec(t, m)) == (t, m)
    np.testing.assert_allclose(sg.to_w(LAM, "lambda"), LAM)
    np.testing.assert_allclose(sg.to_w(LAM, "sqrt") ** 2, LAM)
    for bad in ("log;w=cube", "log;v=lambda", "log;lambda"):
        with pytest.raises(ValueError, match="malformed"):
            sg.split_spec(bad)
    with pytest.raises(ValueError, match="w map"):
        sg.to_w(LAM, "cube")


def test_polynomial_in_lambda_recovered_exactly_and_chosen_by_cross_validation() -> None:
    lam, z = LAM[:, None], -np.log1p(-XI)[None, :]
    log_field = (-1.4 + 0.01 * lam) * (1 - 0.3 * z) + (0.002 * lam**2) * (z**2 - 0.1 * z)  # rank 2, orders (2, 2) in lambda
    field = np.exp(log_field)
    sigma = np.random.default_rng(5).uniform(0.005, 0.2, field.shape)
    model = sg_joint.fit_joint(field, LAM, XI, 2, 2, 2, "log;w=lambda", sigma)
    np.testing.assert_allclose(model(LAM[:, None], XI[None, :]), field, rtol=1e-9)
    # in log(lambda) the same orders cannot represent it
    assert np.abs(sg_joint.fit_joint(field, LAM, XI, 2, 2, 2, "log", sigma)(LAM[:, None], XI[None, :]) / field - 1).max() > 1e-3
    # the closed formula is written in lambda itself and is the model
    formula = sg.closed_formula(model.coef_w, model.coef_z, model.transform, "alpha").split("=", 1)[1]
    assert "w" not in formula.replace("EXP", "")
    value = eval(formula.replace("EXP", "np.exp").replace("^", "**").replace("lambda", "lam"),
                 {"np": np, "lam": 6.5, "z": -np.log1p(-0.45)})
    assert value == pytest.approx(float(model(6.5, 0.45)), rel=1e-12)
    # cross-validation over the maps picks lambda with the true orders
    specs = tuple(sg.model_spec("log", m) for m in sg.W_MAPS)
    best, _ = sg_joint.select_model(field, LAM, XI, specs, 3, 4, 3, None, 0.05)
    assert (best.transform, best.rank, best.order_w, best.order_z) == ("log;w=lambda", 2, 2, 2) and best.score < 1e-9



@pytest.mark.parametrize(("choice", "spec"), [("log", "log"), ("sqrt", "log;w=sqrt")])
def test_joint_stage_uses_the_configured_lambda_map(choice: str, spec: str) -> None:
    scenario = resolve(load_scenario("paper_gt", {**SMALL_OVERRIDES, "surrogate.lambda_map": choice}))
    with pytest.warns(UserWarning, match="reduced to"):
        ds = surrogate.build(scenario, fits.build(scenario, synthetic_cube(scenario, noise=0.0)))
    assert ds.attrs["alpha_transform"] == spec
    assert set(ds["alpha_cv_transform"].values) == {spec}
    # the stored spec is the model: evaluating it reproduces the stage's surrogate values
    values = sg.evaluate(ds["alpha_coef_w"].values, ds["alpha_coef_z"].values, ds["lambda"].values[:, None],
                         ds["xi"].values[None, :], ds["alpha_coef_w"].attrs["transform"])
    np.testing.assert_allclose(values, ds["alpha_surrogate"].values, rtol=1e-12)
