"""`g2tom roughness` on instrument files: SurfaceTopography's own test files (when a directory
holds them) and synthetic X3P files written here, with undefined pixels and a frame around the
measured area (issue 31).

SurfaceTopography's test set (github.com/ContactEngineering/SurfaceTopography,
``test/file_format_examples/``) is third-party data and is not committed here: point the
environment variable :data:`FILES_VARIABLE` at a directory that holds the files named in
:data:`INSTRUMENT_FILES` to run those tests. Their reference is SurfaceTopography's own rms
height of the same file with a plane removed and its undefined pixels left out
(``detrend("height").rms_height_from_area()``).
"""

from __future__ import annotations

import json
import math
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

from g2tom.cli.main import main
from g2tom.heightmap import OUTSIDE_FILL_SHARE, measure
from tests.test_height_fill import PIXEL, punch_holes, rough_surface

#: The environment variable naming the directory with SurfaceTopography's test files.
FILES_VARIABLE = "G2TOM_TOPOGRAPHY_FILES"
#: One file per format of the issue (the first of each present in SurfaceTopography's test set).
INSTRUMENT_FILES = ("al3d-1.al3d", "di-1.di", "opd-1.opd", "sur-2.sur", "x3p-2.x3p")
#: Largest relative difference of the rms height from SurfaceTopography's (the issue's 5 %).
RMS_TOLERANCE = 0.05


def _instrument_file(name: str) -> Path:
    folder = os.environ.get(FILES_VARIABLE)
    if not folder:
        pytest.skip(f"{FILES_VARIABLE} is not set: it names a directory with SurfaceTopography's test files "
                    f"({', '.join(INSTRUMENT_FILES)}), third-party data not committed here")
    path = Path(folder) / name
    if not path.is_file():
        pytest.skip(f"{name} is not in {FILES_VARIABLE} = {folder!r}")
    return path


def _surface_topography_rms(path: Path) -> float:
    """SurfaceTopography's rms height of the file, m: a plane removed, undefined pixels left out."""
    st = pytest.importorskip("SurfaceTopography")
    from g2tom.heightmap import _UNITS

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        topography = st.read_topography(str(path))
        return float(topography.detrend(detrend_mode="height").rms_height_from_area()) * _UNITS[str(topography.unit)]


@pytest.mark.parametrize("name", INSTRUMENT_FILES)
def test_instrument_file_gives_finite_parameters_and_surface_topography_rms(name, capsys) -> None:
    path = _instrument_file(name)
    assert main(["roughness", str(path), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert all(math.isfinite(r[k]) and r[k] > 0 for k in ("sigma", "eta", "beta", "rms_height"))
    reference = _surface_topography_rms(path)
    assert r["rms_height"] == pytest.approx(reference, rel=RMS_TOLERANCE)
    assert 0.0 <= r["filled_share"] <= 0.25
    assert main(["roughness", str(path)]) == 0
    assert "filled      " in capsys.readouterr().out  # the share of filled pixels is printed


def _write_x3p(path: Path, heights: np.ndarray, unit_scale: float = 1.0) -> None:
    """A height map (m, rows y, NaN undefined) as an X3P file through SurfaceTopography's writer."""
    st = pytest.importorskip("SurfaceTopography")
    ny, nx = heights.shape
    # SurfaceTopography's arrays are (x, y); X3P stores heights in m
    topography = st.Topography(np.ma.masked_invalid(heights.T * unit_scale), (nx * PIXEL, ny * PIXEL), unit="m",
                               periodic=False)
    topography.to_x3p(str(path))


def test_synthetic_x3p_with_holes_is_filled_and_measured_like_the_map(tmp_path, capsys) -> None:
    surface = rough_surface()[:128, :96]
    holed = punch_holes(surface, 0.03)
    path = tmp_path / "holed.x3p"
    _write_x3p(path, holed)
    r = measure(path)
    assert r["reader"].startswith("SurfaceTopography") and r["pixel_size"] == pytest.approx([PIXEL, PIXEL], rel=1e-6)
    assert r["shape"] == [128, 96] and r["cropped_to"] is None
    assert r["filled_pixels"] == int(np.isnan(holed).sum())
    np.save(tmp_path / "same.npy", holed)
    from_npy = measure(tmp_path / "same.npy", PIXEL)
    for key in ("rms_height", "m2", "m4", "sigma", "eta", "beta"):
        assert r[key] == pytest.approx(from_npy[key], rel=1e-9), key
    assert r["rms_height"] == pytest.approx(_surface_topography_rms(path), rel=RMS_TOLERANCE)
    assert main(["roughness", str(path)]) == 0
    assert f"filled      {r['filled_pixels']} undefined pixels ({r['filled_share']:.2%})" in capsys.readouterr().out


def test_a_frame_around_the_measured_area_is_cropped_not_filled(tmp_path, capsys) -> None:
    """An instrument's field of view inside a larger frame of undefined pixels (as in a Mountains
    .sur of SurfaceTopography's test set): the rectangle measured is kept, its holes filled."""
    surface = rough_surface()[:96, :80]
    framed = np.full((120, 110), np.nan)
    framed[10:106, 20:100] = punch_holes(surface, 0.02)
    framed[10:30, 20:40] = np.nan  # a notch of the frame: outside the rectangle kept
    path = tmp_path / "framed.x3p"
    _write_x3p(path, framed)
    r = measure(path)
    assert r["read_shape"] == [120, 110]
    (r0, r1), (c0, c1) = r["cropped_to"]
    kept = framed[r0:r1 + 1, c0:c1 + 1]
    # the largest rectangle without the frame: below the notch (76 x 80 beats 96 x 60 beside it),
    # a few rows lower where a punched hole joins the notch
    assert 30 <= r0 <= 36 and r1 == 105 and (c0, c1) == (20, 99) and r["shape"] == list(kept.shape)
    assert r["filled_pixels"] == int(np.isnan(kept).sum()) and r["filled_share"] < 0.03
    np.save(tmp_path / "kept.npy", kept)
    assert r["rms_height"] == pytest.approx(measure(tmp_path / "kept.npy", PIXEL)["rms_height"], rel=1e-9)
    assert main(["roughness", str(path)]) == 0
    assert f"cropped     to rows {r0}..{r1}, columns {c0}..{c1} of the 120 x 110 map read" in capsys.readouterr().out


def test_a_few_edge_dropouts_are_filled_not_cropped(tmp_path) -> None:
    surface = rough_surface()[:64, :64].copy()
    surface[0, 5:9] = np.nan  # a region of 4 pixels on the border: < OUTSIDE_FILL_SHARE of the map
    assert 4 / surface.size <= OUTSIDE_FILL_SHARE
    np.save(tmp_path / "edge.npy", surface)
    r = measure(tmp_path / "edge.npy", PIXEL)
    assert r["cropped_to"] is None and r["filled_pixels"] == 4 and r["shape"] == [64, 64]


def test_largest_rectangle_against_brute_force() -> None:
    from g2tom.heightmap import _largest_rectangle

    rng = np.random.default_rng(4)
    for _ in range(20):
        inside = rng.uniform(size=(9, 11)) > 0.25
        (r0, r1), (c0, c1) = _largest_rectangle(inside)
        assert inside[r0:r1 + 1, c0:c1 + 1].all()
        best = max(((b - a + 1) * (d - c + 1) for a in range(9) for b in range(a, 9) for c in range(11)
                    for d in range(c, 11) if inside[a:b + 1, c:d + 1].all()), default=0)
        assert (r1 - r0 + 1) * (c1 - c0 + 1) == best
