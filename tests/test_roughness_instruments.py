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
    assert r["shape"] == [128, 96] and r["measured_pixels"] == r["used_pixels"] == 128 * 96 - r["filled_pixels"]
    assert r["filled_pixels"] == int(np.isnan(holed).sum())
    np.save(tmp_path / "same.npy", holed)
    from_npy = measure(tmp_path / "same.npy", PIXEL)
    for key in ("rms_height", "m2", "m4", "sigma", "eta", "beta"):
        assert r[key] == pytest.approx(from_npy[key], rel=1e-9), key
    assert r["rms_height"] == pytest.approx(_surface_topography_rms(path), rel=RMS_TOLERANCE)
    assert main(["roughness", str(path)]) == 0
    assert f"filled      {r['filled_pixels']} undefined pixels ({r['filled_share']:.2%})" in capsys.readouterr().out


def test_a_frame_around_the_measured_area_is_masked_not_filled(tmp_path, capsys) -> None:
    """An instrument's field of view inside a larger frame of undefined pixels (as in a Mountains
    .sur of SurfaceTopography's test set): the measured area is kept whole, its holes filled, the
    frame masked."""
    surface = rough_surface()[:96, :80]
    framed = np.full((120, 110), np.nan)
    framed[10:106, 20:100] = punch_holes(surface, 0.02)
    framed[10:30, 20:40] = np.nan  # a notch of the frame: outside the measured area
    path = tmp_path / "framed.x3p"
    _write_x3p(path, framed)
    r = measure(path)
    from g2tom.heightmap import measured_area

    area = measured_area(framed)
    inside = area.inside
    field = np.zeros(framed.shape, dtype=bool)
    field[10:106, 20:100] = True
    field[10:30, 20:40] = False
    # the field of view less the punched holes that touch the frame (they join it)
    assert not inside[~field].any() and 0 < (field & ~inside).sum() < 0.01 * field.sum()
    holes = int(np.isnan(framed[inside]).sum())
    assert r["shape"] == [120, 110] and r["estimator"] == "masked spectrum of the measured area"
    assert r["filled_pixels"] == area.filled == holes > 0
    assert r["filled_share"] == pytest.approx(holes / inside.sum(), rel=1e-12)
    assert r["measured_pixels"] == r["used_pixels"] == int((~np.isnan(framed)).sum()) and r["used_share"] == 1.0
    # the rms height of the whole measured area (holes filled, plane removed), not of a rectangle in it
    yy, xx = np.nonzero(inside)
    design = np.column_stack([np.ones(yy.size), xx, yy])
    coef, *_ = np.linalg.lstsq(design, area.heights[inside], rcond=None)
    direct = float(np.std(area.heights[inside] - design @ coef))
    assert r["rms_height"] == pytest.approx(direct, rel=1e-6)  # the file holds float32 heights
    assert main(["roughness", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"measured    {r['measured_pixels']} of 13200 pixels" in out and "used: all of them" in out


def test_a_few_edge_dropouts_are_filled_not_cropped(tmp_path) -> None:
    surface = rough_surface()[:64, :64].copy()
    surface[0, 5:9] = np.nan  # a region of 4 pixels on the border: < OUTSIDE_FILL_SHARE of the map
    assert 4 / surface.size <= OUTSIDE_FILL_SHARE
    np.save(tmp_path / "edge.npy", surface)
    r = measure(tmp_path / "edge.npy", PIXEL)
    assert r["estimator"] == "spectrum of the whole map" and r["filled_pixels"] == 4 and r["shape"] == [64, 64]
