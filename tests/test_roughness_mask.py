"""`g2tom roughness` on maps whose measured area is not the whole map (a disc or an L-shaped field
of view in a frame of undefined pixels): the statistics of the measured area, masked, not of a
rectangle cropped from it."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.heightmap import MAX_MISSING_SHARE, measure, measured_area
from tests.test_height_fill import N, PIXEL, punch_holes, rough_surface

_Y, _X = np.mgrid[0:N, 0:N]
#: Measured areas: a disc in a ring of undefined pixels that reaches the border, and an L.
AREAS = {
    "disc": (_Y - 127.5) ** 2 + (_X - 127.5) ** 2 <= 120**2,
    "L": ~((_Y < 128) & (_X >= 128)),
}
#: m2 and m4 of the measured area against the complete map's (both spectral, 4 px cutoff): the
#: area is a sample of the surface; on seed 0, -0.4 ... +0.8 % (m2) and -1.7 ... -1.4 % (m4).
MOMENT_TOLERANCE = 0.03


def _direct_rms(heights: np.ndarray, inside: np.ndarray) -> float:
    """rms height over the pixels of ``inside``, their least-squares plane removed, m."""
    yy, xx = np.nonzero(inside)
    design = np.column_stack([np.ones(yy.size), xx, yy])
    coef, *_ = np.linalg.lstsq(design, heights[inside], rcond=None)
    return float(np.sqrt(np.mean((heights[inside] - design @ coef) ** 2)))


@pytest.fixture(scope="module")
def surface() -> np.ndarray:
    return rough_surface()


@pytest.fixture(scope="module")
def complete(tmp_path_factory, surface) -> dict:
    path = tmp_path_factory.mktemp("complete") / "complete.npy"
    np.save(path, surface)
    return measure(path, PIXEL)


@pytest.mark.parametrize("name", list(AREAS))
def test_measured_area_gives_its_own_statistics(tmp_path, surface, complete, name) -> None:
    inside = AREAS[name]
    masked = np.where(inside, surface, np.nan)
    np.save(tmp_path / "masked.npy", masked)
    r = measure(tmp_path / "masked.npy", PIXEL)
    assert r["shape"] == [N, N] and r["estimator"] == "masked spectrum of the measured area"
    assert r["measured_pixels"] == int(inside.sum()) and r["map_pixels"] == N * N
    assert r["used_pixels"] >= 0.95 * r["measured_pixels"] and r["used_share"] >= 0.95
    assert r["filled_pixels"] == 0
    # rms height: that of the measured pixels (their plane removed), and near the complete map's
    assert r["rms_height"] == pytest.approx(_direct_rms(surface, inside), rel=1e-12)
    assert r["rms_height"] == pytest.approx(complete["rms_height"], rel=0.02)
    assert r["m2"] == pytest.approx(complete["m2"], rel=MOMENT_TOLERANCE)
    assert r["m4"] == pytest.approx(complete["m4"], rel=MOMENT_TOLERANCE)
    for key in ("sigma", "eta", "beta"):
        assert np.isfinite(r[key]) and r[key] > 0


def test_disc_in_a_ring_is_not_a_strip(tmp_path, surface) -> None:
    """A disc cut by a narrow notch of the frame: the largest rectangle in it would be a strip; the
    masked statistics use the whole disc, and are those of the disc without the notch (rms height
    within 2 %, m2 and m4 within :data:`MOMENT_TOLERANCE`: the notch reshapes the window)."""
    disc = AREAS["disc"]
    notched = disc & ~((_X > 60) & (np.abs(_Y - 127.5) < 4))  # a slot from the ring to near the centre
    np.save(tmp_path / "disc.npy", np.where(disc, surface, np.nan))
    np.save(tmp_path / "notched.npy", np.where(notched, surface, np.nan))
    whole, r = measure(tmp_path / "disc.npy", PIXEL), measure(tmp_path / "notched.npy", PIXEL)
    assert r["measured_pixels"] == r["used_pixels"] == int(notched.sum()) > 0.9 * int(disc.sum())
    assert r["rms_height"] == pytest.approx(_direct_rms(surface, notched), rel=1e-12)
    assert r["rms_height"] == pytest.approx(whole["rms_height"], rel=0.02)
    for key in ("m2", "m4"):
        assert r[key] == pytest.approx(whole[key], rel=MOMENT_TOLERANCE), key


def test_holes_inside_are_filled_and_the_outside_stays_nan(surface) -> None:
    inside = AREAS["disc"]
    holed = np.where(inside, punch_holes(surface, 0.04, seed=3), np.nan)
    area = measured_area(holed)
    np.testing.assert_array_equal(area.inside, inside & (~np.isnan(holed) | _touches_nothing_outside(holed, inside)))
    holes = np.isnan(holed) & area.inside
    assert area.filled == int(holes.sum()) > 0
    assert np.isnan(area.heights[~area.inside]).all() and np.isfinite(area.heights[area.inside]).all()
    np.testing.assert_array_equal(area.heights[~np.isnan(holed)], holed[~np.isnan(holed)])
    # a complete map: itself, nothing filled
    whole = measured_area(surface)
    assert whole.inside.all() and whole.filled == 0
    np.testing.assert_array_equal(whole.heights, surface)


def _touches_nothing_outside(holed: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Undefined pixels of regions that do not reach the area's outside (the holes proper)."""
    from scipy import ndimage

    labels, _ = ndimage.label(np.isnan(holed))
    outside_labels = np.unique(labels[~inside])
    return ~np.isin(labels, outside_labels)


def test_measured_area_refusals(surface) -> None:
    with pytest.raises(ConfigError) as info:
        measured_area(np.full((8, 9), np.nan))
    assert str(info.value) == "height map holds no defined pixel: all 72 pixels are undefined (NaN)"
    inside = AREAS["disc"]
    holed = np.where(inside, punch_holes(surface, MAX_MISSING_SHARE + 0.03, seed=5), np.nan)
    with pytest.raises(ConfigError) as info:
        measured_area(holed)
    message = str(info.value)
    assert "\n" not in message and "of the measured area are undefined" in message and "25%" in message


def test_too_narrow_an_area_is_refused_in_one_line(tmp_path, surface) -> None:
    strip = np.full((N, N), np.nan)
    strip[100:112, :] = surface[100:112, :]  # 12 px wide: a quarter of its largest disc < 4 px
    np.save(tmp_path / "strip.npy", strip)
    with pytest.raises(ConfigError) as info:
        measure(tmp_path / "strip.npy", PIXEL)
    message = str(info.value)
    assert "\n" not in message and "cutoff wavelength = 4e-06 m is out of range" in message
    assert "measured area's largest disc" in message


def test_cli_says_how_much_it_used(tmp_path, capsys, surface) -> None:
    inside = AREAS["disc"]
    path = tmp_path / "disc.npy"
    np.save(path, np.where(inside, surface, np.nan))
    count = int(inside.sum())
    assert main(["roughness", str(path), "--pixel-size", str(PIXEL)]) == 0
    out = capsys.readouterr().out
    assert (f"measured    {count} of {N * N} pixels ({count / N**2:.1%}) used: all of them "
            "(masked spectrum of the measured area)") in out
    assert "filled      none (no undefined pixels inside the measured area)" in out
    assert main(["roughness", str(path), "--pixel-size", str(PIXEL), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert (r["measured_pixels"], r["used_pixels"], r["used_share"]) == (count, count, 1.0)
    np.save(tmp_path / "complete.npy", surface)
    assert main(["roughness", str(tmp_path / "complete.npy"), "--pixel-size", str(PIXEL)]) == 0
    assert (f"measured    {N * N} of {N * N} pixels (100.0%) used: all of them (spectrum of the whole map)"
            in capsys.readouterr().out)


@pytest.mark.parametrize("name", list(AREAS))
def test_rms_height_as_surface_topography(tmp_path, surface, name) -> None:
    st = pytest.importorskip("SurfaceTopography")
    masked = np.where(AREAS[name], surface, np.nan)
    path = tmp_path / "masked.nc"
    # SurfaceTopography's arrays are (x, y), here in um with the outside masked
    st.Topography(np.ma.masked_invalid(masked.T * 1e6), (N * 1.0, N * 1.0), unit="um", periodic=False
                  ).to_netcdf(str(path))
    r = measure(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        topography = st.read_topography(str(path))
        reference = float(topography.detrend(detrend_mode="height").rms_height_from_area()) * 1e-6
    assert r["measured_pixels"] == int(AREAS[name].sum())
    assert r["rms_height"] == pytest.approx(reference, rel=0.02)
