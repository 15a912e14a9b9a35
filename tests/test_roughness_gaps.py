"""`g2tom roughness` on height maps with undefined (NaN) pixels (issue 31)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.heightmap import MAX_MISSING_SHARE, measure
from tests.test_height_fill import PIXEL, punch_holes, rough_surface


@pytest.fixture(scope="module")
def surface() -> np.ndarray:
    return rough_surface()


def test_measure_fills_and_reports(tmp_path, surface) -> None:
    holed = punch_holes(surface, 0.05)
    missing = int(np.isnan(holed).sum())
    np.save(tmp_path / "complete.npy", surface)
    np.save(tmp_path / "holed.npy", holed)
    complete = measure(tmp_path / "complete.npy", PIXEL)
    r = measure(tmp_path / "holed.npy", PIXEL)
    assert r["filled_pixels"] == missing
    assert r["filled_share"] == pytest.approx(missing / holed.size, rel=1e-12)
    assert complete["filled_pixels"] == 0 and complete["masked_m4_change"] is None
    # the filled map's moments near the complete map's (height_fill's test: m4 biased up 2 ... 3.5 %)
    assert r["rms_height"] == pytest.approx(complete["rms_height"], rel=0.02)
    assert r["m2"] == pytest.approx(complete["m2"], rel=0.02)
    assert r["m4"] == pytest.approx(complete["m4"], rel=0.04)
    # masked: the defined pixels' rms within 1 % of the complete map's; the finite-difference
    # m4 of the filled map carries the fill's kinks in full, so masking lowers it by several %
    assert r["masked_rms_height"] == pytest.approx(complete["rms_height"], rel=0.01)
    assert abs(r["masked_rms_change"]) < 0.01 and abs(r["masked_m2_change"]) < 0.02
    assert -0.15 < r["masked_m4_change"] < 0


def test_measure_refuses_too_many_missing(tmp_path, surface) -> None:
    holed = punch_holes(surface, MAX_MISSING_SHARE + 0.02)
    path = tmp_path / "mostly_holes.npy"
    np.save(path, holed)
    share = np.isnan(holed).mean()
    with pytest.raises(ConfigError) as info:
        measure(path, PIXEL)
    message = str(info.value)
    assert str(path) in message and f"{share:.1%}" in message and "25%" in message
    assert message.count("HEIGHTMAP") == 1


def test_cli_prints_the_filled_share(tmp_path, capsys, surface) -> None:
    holed = punch_holes(surface[:64, :64], 0.03)
    path = tmp_path / "map.npy"
    np.save(path, holed)
    share = np.isnan(holed).mean()
    assert main(["roughness", str(path), "--pixel-size", str(PIXEL)]) == 0
    out = capsys.readouterr().out
    assert f"filled      {int(np.isnan(holed).sum())} undefined pixels ({share:.2%})" in out
    assert main(["roughness", str(path), "--pixel-size", str(PIXEL), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["filled_share"] == pytest.approx(share, rel=1e-12)
    assert set(result) >= {"masked_rms_height", "masked_rms_change", "masked_m2_change", "masked_m4_change"}


def test_cli_map_without_gaps_says_so(tmp_path, capsys, surface) -> None:
    np.save(tmp_path / "map.npy", surface[:64, :64])
    assert main(["roughness", str(tmp_path / "map.npy"), "--pixel-size", str(PIXEL)]) == 0
    assert "filled      none (no undefined pixels)" in capsys.readouterr().out


def test_instrument_file_with_undefined_data(tmp_path, surface) -> None:
    st = pytest.importorskip("SurfaceTopography")
    holed = punch_holes(surface[:64, :64], 0.04)
    path = tmp_path / "scan.nc"
    # SurfaceTopography's arrays are (x, y), here in um with undefined data masked
    st.Topography(np.ma.masked_invalid(holed.T * 1e6), (64.0, 64.0), unit="um", periodic=False).to_netcdf(str(path))
    r = measure(path)
    assert r["reader"].startswith("SurfaceTopography") and r["pixel_size"] == pytest.approx([PIXEL, PIXEL], rel=1e-6)
    assert r["filled_pixels"] == np.isnan(holed).sum()
    np.save(tmp_path / "same.npy", holed)
    assert r["rms_height"] == pytest.approx(measure(tmp_path / "same.npy", PIXEL)["rms_height"], rel=1e-5)  # float32 file
