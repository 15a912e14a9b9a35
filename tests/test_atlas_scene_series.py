"""The atlas's scene-series surrogate: each scene's series in ln F', interpolated across (ln mu, ln Pi)
by a radial basis function. Oracles: a response linear in (ln mu, ln Pi) reproduced exactly
anywhere (the linear tail), every scene's own series reproduced at its own groups (interpolation),
and the leave-one-scene-out residuals against a fold fitted by hand."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from numpy.polynomial import chebyshev

from g2tom.atlas.fit import FORMAT, FORMAT_VERSION, curve_doc, curve_model
from scipy.interpolate import RBFInterpolator

from g2tom.fitting.atlas_grid import FRAMES, fit_grid_tensor, group_coordinates, node_coordinates
from g2tom.fitting import atlas_grid
from g2tom.fitting.atlas_scene_series import KERNELS, TAIL_DEGREE, cross_validate, fit_scene_series

XI = np.array([0.0, 0.3, 0.7])
LAM = np.array([1.0, 5.0])
Z, W = node_coordinates(XI, LAM)
FORCE = np.geomspace(0.05, 20.0, 9)


def _scenes(response, n: int = 9, seed: int = 4) -> dict[str, np.ndarray]:
    """Points of ``n`` scenes scattered over mu 1..50, Pi 5..320, ln R' = response(ln mu, ln Pi, ln F', z, w)."""
    rng = np.random.default_rng(seed)
    mu, pi = np.exp(rng.uniform(0, np.log(50), n)), np.exp(rng.uniform(np.log(5), np.log(320), n))
    scene = np.repeat(np.arange(n), FORCE.size)
    m, p, f = np.log(mu)[scene], np.log(pi)[scene], np.log(np.tile(FORCE, n))
    log_r = response(m[:, None, None], p[:, None, None], f[:, None, None], Z[None, :, None], W[None, None, :])
    return {"mu": mu[scene], "Pi": pi[scene], "force": np.exp(f), "scene": scene, "log_r": log_r,
            "sigma": np.full(log_r.shape, 0.02)}


def _linear(m, p, f, z, w):
    """Linear in (ln mu, ln Pi), cubic in ln F', other at every node."""
    return 0.3 - 0.2 * m + 0.1 * p * (1 + z) - (0.6 + 0.05 * w) * f + 0.02 * f**3 + z * (1 + 0.1 * w)


def _bent(m, p, f, z, w):
    """Curved in (ln mu, ln Pi): no polynomial tail reproduces it."""
    return np.sin(m) * np.cos(0.7 * p) - 0.5 * f + z * (1 + np.sin(0.5 * m) * w)


def _fit(pts, **kw):
    args = dict(order=3, kernel="cubic", smoothing=0.0) | kw
    return fit_scene_series(Z, W, pts["mu"], pts["Pi"], pts["force"], pts["log_r"], pts["sigma"], pts["scene"],
                            **args)


def _at(model, mu, pi, force):
    """ln R' at every node of (XI, LAM) for a surface and loads: (loads, nz, nw)."""
    x, l, f = np.meshgrid(XI, LAM, force, indexing="ij")
    out = model.log_resistance(x.ravel(), l.ravel(), np.full(x.size, mu), np.full(x.size, pi), f.ravel())
    return out.reshape(x.shape).transpose(2, 0, 1)


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("smoothing", [0.0, 0.3])
def test_a_response_linear_in_the_groups_is_reproduced_anywhere(kernel: str, smoothing: float) -> None:
    model = _fit(_scenes(_linear), kernel=kernel, smoothing=smoothing)
    force = np.geomspace(0.06, 18.0, 7)
    for mu, pi in ((2.0, 40.0), (33.0, 9.0), (7.0, 250.0)):  # between scenes, off every one
        expected = _linear(np.log(mu), np.log(pi), np.log(force)[:, None, None], Z[None, :, None], W[None, None, :])
        assert np.max(np.abs(_at(model, mu, pi, force) - expected)) < 1e-9


def _quadratic(m, p, f, z, w):
    """Quadratic in (ln mu, ln Pi), cubic in ln F', other at every node."""
    return 0.3 - 0.2 * m + 0.1 * p + 0.04 * m**2 - 0.03 * m * p * (1 + z) + 0.02 * p**2 - 0.6 * f + 0.02 * f**3 + z * w


@pytest.mark.parametrize("smoothing", [0.0, 3.0])
def test_the_quintic_reproduces_a_response_quadratic_in_the_groups_and_the_cubic_does_not(smoothing: float) -> None:
    """The quintic's quadratic tail holds a quadratic exactly at any smoothing (smoothing acts on the
    radial part only); the cubic's linear tail bends between the scenes."""
    pts = _scenes(_quadratic, n=12)
    force = np.geomspace(0.06, 18.0, 7)
    errors = {}
    for kernel in ("quintic", "cubic"):
        model = _fit(pts, kernel=kernel, smoothing=smoothing)
        errors[kernel] = max(np.max(np.abs(_at(model, mu, pi, force) - _quadratic(
            np.log(mu), np.log(pi), np.log(force)[:, None, None], Z[None, :, None], W[None, None, :])))
            for mu, pi in ((2.0, 40.0), (33.0, 9.0), (7.0, 250.0)))
    assert errors["quintic"] < 1e-8 and errors["cubic"] > 1e-3
    assert TAIL_DEGREE == {"cubic": 1, "thin_plate_spline": 1, "quintic": 2}


def test_between_nodes_linear_and_the_clean_node_is_the_clean_curve() -> None:
    model = _fit(_scenes(_linear))
    xi = 0.5  # z = ln 2, between nodes 0.3 and 0.7 in z
    z = -np.log1p(-xi)
    t = (z - Z[1]) / (Z[2] - Z[1])
    at = lambda x: model.log_resistance(np.array([x]), np.array([2.0]), np.array([5.0]), np.array([30.0]),  # noqa: E731
                                        np.array([1.0]))[0]
    assert at(xi) == pytest.approx((1 - t) * at(0.3) + t * at(0.7), abs=1e-12)
    assert at(0.0) == pytest.approx(_linear(np.log(5.0), np.log(30.0), 0.0, 0.0, np.log(2.0)), abs=1e-9)


def test_without_smoothing_every_scene_keeps_its_own_series() -> None:
    pts = _scenes(_bent)
    model = _fit(pts, order=5)
    for s in range(3):
        own = pts["scene"] == s
        for i in range(XI.size):
            for j in range(LAM.size):
                series = chebyshev.chebfit(2 * (np.log(pts["force"][own]) - model.load_low)
                                           / (model.load_high - model.load_low) - 1, pts["log_r"][own, i, j], 5)
                at = _at(model, pts["mu"][own][0], pts["Pi"][own][0], pts["force"][own])[:, i, j]
                assert np.max(np.abs(at - chebyshev.chebval(2 * (np.log(pts["force"][own]) - model.load_low)
                                                             / (model.load_high - model.load_low) - 1, series))) < 1e-9
    # smoothing lets it pass off a scene's own values; they pull it less the more it smooths
    own = pts["scene"] == 0
    gap = [np.max(np.abs(_at(_fit(pts, order=5, smoothing=s), pts["mu"][own][0], pts["Pi"][own][0],
                              pts["force"][own]) - pts["log_r"][own])) for s in (0.1, 10.0)]
    assert 1e-6 < gap[0] < gap[1]


def test_leave_one_scene_out_predicts_each_scene_from_the_others() -> None:
    pts = _scenes(_bent)
    residual = cross_validate(Z, W, pts["mu"], pts["Pi"], pts["force"], pts["log_r"], pts["sigma"], pts["scene"],
                              3, "cubic", 0.1)
    load = (float(np.log(pts["force"]).min()), float(np.log(pts["force"]).max()))
    out = pts["scene"] == 4
    keep = ~out
    by_hand = fit_scene_series(Z, W, pts["mu"][keep], pts["Pi"][keep], pts["force"][keep], pts["log_r"][keep],
                               pts["sigma"][keep], pts["scene"][keep], 3, "cubic", 0.1, load)
    expected = _at(by_hand, pts["mu"][out][0], pts["Pi"][out][0], pts["force"][out]) - pts["log_r"][out]
    assert np.max(np.abs(residual[out] - expected)) < 1e-12
    assert np.all(np.isfinite(residual)) and np.sqrt(np.mean(residual**2)) > 0.01  # bent: not reproduced
    linear = _scenes(_linear)
    assert np.max(np.abs(cross_validate(Z, W, linear["mu"], linear["Pi"], linear["force"], linear["log_r"],
                                        linear["sigma"], linear["scene"], 3, "thin_plate_spline", 0.0))) < 1e-8


def test_refuses_scenes_on_a_line_too_few_points_and_an_unknown_kernel() -> None:
    pts = _scenes(_linear, n=3)
    line = {**pts, "Pi": pts["mu"] * 3.0}  # every scene on ln Pi = ln mu + ln 3
    with pytest.raises(ValueError, match="on one line"):
        _fit(line)
    few = {k: v[pts["scene"] != 2] for k, v in pts.items()}
    with pytest.raises(ValueError, match="on one line"):  # two scenes
        _fit(few)
    with pytest.raises(ValueError, match="finite points cannot fit"):
        _fit(pts, order=9)
    with pytest.raises(ValueError, match="kernel 'gaussian'"):
        _fit(pts, kernel="gaussian")
    five = _scenes(_linear, n=5)  # fix a plane, not the quintic's quadratic tail (six terms)
    assert np.isfinite(_at(_fit(five, kernel="cubic"), 3.0, 30.0, FORCE)).all()
    with pytest.raises(ValueError, match="cannot fix the quintic kernel's tail of degree 2"):
        _fit(five, kernel="quintic")
    rows = _scenes(_linear, n=8)  # eight scenes on two rows of Pi: no term in (ln Pi)^2
    rows["Pi"] = np.where(rows["scene"] % 2 == 0, 10.0, 100.0)
    with pytest.raises(ValueError, match="cannot fix the quintic"):
        _fit(rows, kernel="quintic")
    assert np.all(np.isinf(cross_validate(Z, W, five["mu"], five["Pi"], five["force"], five["log_r"], five["sigma"],
                                          five["scene"], 3, "quintic", 0.0)))
    # a scene whose own series cannot be fitted spoils every fold but its own
    holed = _scenes(_linear, n=7)
    holed["log_r"][(holed["scene"] == 2) & (holed["force"] > 0.3)] = np.nan  # 3 finite steps for P = 3
    residual = cross_validate(Z, W, holed["mu"], holed["Pi"], holed["force"], holed["log_r"], holed["sigma"],
                              holed["scene"], 3, "cubic", 0.0)
    assert np.all(np.isinf(residual[holed["scene"] != 2]))
    own = residual[holed["scene"] == 2]
    assert np.max(np.abs(own[np.isfinite(own)])) < 1e-8 and np.isfinite(own).sum() == 3 * XI.size * LAM.size
    # a fold that cannot be fitted (two scenes left) stays inf
    assert np.all(np.isinf(cross_validate(Z, W, pts["mu"], pts["Pi"], pts["force"], pts["log_r"], pts["sigma"],
                                          pts["scene"], 3, "cubic", 0.0)))


def test_both_kinds_survive_their_document() -> None:
    pts = _scenes(_bent)
    series = _fit(pts, order=5, smoothing=0.3)
    grid = fit_grid_tensor(Z, W, pts["mu"], pts["Pi"], pts["force"], pts["log_r"], pts["sigma"], (2, 2), 3)
    query = (np.full(4, 0.5), np.full(4, 3.0), np.array([1.5, 9.0, 20.0, 40.0]), np.array([8.0, 60.0, 100.0, 300.0]),
             np.array([0.07, 0.9, 4.0, 15.0]))
    sheared = [_fit(pts, order=5, smoothing=0.3, frame="sheared"),
               fit_grid_tensor(Z, W, pts["mu"], pts["Pi"], pts["force"], pts["log_r"], pts["sigma"], (2, 2), 3,
                               frame="sheared")]
    for model in [series, grid] + sheared:
        again = curve_model(json.loads(json.dumps(curve_doc(model))))
        assert type(again) is type(model) and again.frame == model.frame
        assert np.array_equal(again.log_resistance(*query), model.log_resistance(*query))
    for model in sheared:  # the frame is what makes them answer otherwise
        assert np.max(np.abs(model.log_resistance(*query) - dataclasses.replace(model, frame="log").log_resistance(
            *query))) > 0.01
    # a document of format 2 or 3 has no frame: it was built in (ln mu, ln Pi)
    older = {k: v for k, v in curve_doc(grid).items() if k != "frame"}
    assert np.array_equal(curve_model(older).log_resistance(*query), grid.log_resistance(*query))
    with pytest.raises(ValueError, match="unknown curve model kind 'spline'"):
        curve_model({**curve_doc(grid), "kind": "spline"})
    with pytest.raises(ValueError, match="unknown frame 'polar'"):
        curve_model({**curve_doc(grid), "frame": "polar"})
    assert FORMAT == "g2tom-atlas-surrogate" and FORMAT_VERSION == 4


def _along_the_diagonal(m, p, f, z, w):
    """A cubic in ln(mu / Pi) alone (the sheared frame's first coordinate), other at every node."""
    u = m - p
    return 0.4 + 0.3 * u - 0.05 * u**2 + 0.004 * u**3 - (0.6 + 0.05 * w) * f + z * (1 + 0.1 * u)


def test_the_sheared_frame_holds_a_response_along_mu_over_pi() -> None:
    """In (ln(mu / Pi), ln Pi) the grid's degree (3, 0) is every cubic in ln(mu / Pi): such a response is
    reproduced anywhere; in (ln mu, ln Pi) the same degree is cubic in ln mu alone and misses it."""
    pts = _scenes(_along_the_diagonal, n=12)
    force = np.geomspace(0.06, 18.0, 7)
    errors = {}
    for frame in FRAMES:
        model = fit_grid_tensor(Z, W, pts["mu"], pts["Pi"], pts["force"], pts["log_r"], pts["sigma"], (3, 0), 3,
                                frame=frame)
        errors[frame] = max(np.max(np.abs(_at(model, mu, pi, force) - _along_the_diagonal(
            np.log(mu), np.log(pi), np.log(force)[:, None, None], Z[None, :, None], W[None, None, :])))
            for mu, pi in ((2.0, 40.0), (33.0, 9.0), (7.0, 250.0)))
    assert errors["sheared"] < 1e-9 and errors["log"] > 0.05
    np.testing.assert_array_equal(group_coordinates(np.array([2.0, 6.0]), np.array([8.0, 3.0]), "sheared"),
                                  [[np.log(2.0) - np.log(8.0), np.log(8.0)], [np.log(6.0) - np.log(3.0), np.log(3.0)]])
    with pytest.raises(ValueError, match="frame 'polar'"):
        atlas_grid.group_coordinates(np.ones(2), np.ones(2), "polar")


def test_the_scene_series_interpolates_in_its_frame() -> None:
    """The sheared series equals scipy's RBF through the scenes' series at (ln mu - ln Pi, ln Pi)."""
    pts = _scenes(_bent)
    model = _fit(pts, order=3, smoothing=0.3, frame="sheared")
    centers = np.array([[np.log(pts["mu"][pts["scene"] == s][0] / pts["Pi"][pts["scene"] == s][0]),
                         np.log(pts["Pi"][pts["scene"] == s][0])] for s in range(9)])
    np.testing.assert_allclose(model.centers, centers, rtol=0, atol=1e-14)
    by_hand = RBFInterpolator(centers, model.coef.reshape(9, -1), kernel="cubic", smoothing=0.3, degree=1)
    mu, pi = 13.0, 21.0
    coef = by_hand(np.array([[np.log(mu / pi), np.log(pi)]])).reshape(model.coef.shape[1:])
    force = np.array([0.2, 3.0])
    basis = chebyshev.chebvander(2 * (np.log(force) - model.load_low) / (model.load_high - model.load_low) - 1, 3)
    expected = np.einsum("zwq,fq->fzw", coef, basis)
    assert np.max(np.abs(_at(model, mu, pi, force) - expected)) < 1e-12
