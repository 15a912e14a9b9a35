"""Spectral moments below a cutoff, summit parameters, and measured topographies through the CLI."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from g2tom.cli.main import main
from g2tom.physics.surface_spectrum import psd_moments, summit_parameters
from tests.test_roughness import PIXEL, wave_surface

N = 256


@pytest.fixture(scope="module")
def surface():
    return wave_surface(N)


def _with_short_wave(z: np.ndarray) -> np.ndarray:
    """Adds a wave of 256/80 = 3.2 pixels, shorter than a 4-pixel cutoff."""
    x = np.arange(z.shape[1]) * PIXEL
    return z + 0.3e-6 * np.cos(2 * np.pi * 80 * x / (z.shape[1] * PIXEL))[None, :]


def test_periodic_moments_match_the_closed_forms_below_the_cutoff(surface) -> None:
    z, m0, m2, m4 = surface
    got = psd_moments(_with_short_wave(z), (PIXEL, PIXEL), 4 * PIXEL, periodic=True)
    assert (got.detrending, got.window) == ("mean", "none")
    assert got.m0 == pytest.approx(m0, rel=1e-10)
    assert got.m2 == pytest.approx(m2, rel=1e-10)
    assert got.m4 == pytest.approx(m4, rel=1e-10)
    assert got.rms_height == pytest.approx(np.sqrt(m0 + 0.3e-6**2 / 2), rel=1e-10)  # every wavelength
    # a cutoff below the short wave counts it: its m4 share is 3/16 A^2 k^4
    k = 2 * np.pi * 80 / (N * PIXEL)
    fine = psd_moments(_with_short_wave(z), (PIXEL, PIXEL), 2 * PIXEL, periodic=True)
    assert fine.m4 == pytest.approx(m4 + 3 / 16 * 0.3e-6**2 * k**4, rel=1e-10)


def test_measured_map_windowed_with_tilt_and_offset(surface) -> None:
    z, m0, m2, m4 = surface
    tilted = z + 3e-6 + 1e-3 * np.arange(N)[None, :] * PIXEL + 4e-4 * np.arange(N)[:, None] * PIXEL
    got = psd_moments(tilted, (PIXEL, PIXEL), 4 * PIXEL)
    assert (got.detrending, got.window) == ("plane", "hann")
    assert got.m0 == pytest.approx(m0, rel=0.03)
    assert got.m2 == pytest.approx(m2, rel=0.03)
    assert got.m4 == pytest.approx(m4, rel=0.03)


def test_rectangular_pixels(surface) -> None:
    """The same surface sampled every other pixel along x: same moments (dy, dx) = (h, 2h)."""
    z, m0, m2, m4 = surface
    got = psd_moments(z[:, ::2], (PIXEL, 2 * PIXEL), 8 * PIXEL, periodic=True)
    assert (got.m0, got.m2, got.m4) == pytest.approx((m0, m2, m4), rel=1e-10)


def test_summit_parameters_by_hand() -> None:
    s = summit_parameters(1.0, 1.0, 3.0)  # alpha = 3
    assert s.bandwidth == 3.0
    assert s.sigma == pytest.approx(np.sqrt(1 - 0.8968 / 3), rel=1e-14)
    assert s.summit_mean_height == pytest.approx(4 / np.sqrt(3 * np.pi), rel=1e-14)
    assert s.eta == pytest.approx(3 / (6 * np.pi * np.sqrt(3)), rel=1e-14)
    assert s.beta == pytest.approx(0.737 / np.sqrt(3), rel=1e-14)
    nayak = summit_parameters(1.0, 1.0, 3.0, "nayak")
    assert nayak.beta == pytest.approx(0.375 * np.sqrt(np.pi / 3), rel=1e-14)
    assert s.beta / nayak.beta == pytest.approx(1.109, abs=5e-4)  # the 10.9 %
    with pytest.raises(ValueError, match="alpha"):
        summit_parameters(1.0, 1.0, 1.0)


def _periodic_topography(z: np.ndarray, unit: str, periodic: bool = True):
    st = pytest.importorskip("SurfaceTopography")
    scale = {"nm": 1e9, "um": 1e6, "mm": 1e3}[unit]
    ny, nx = z.shape
    # SurfaceTopography's arrays are (x, y)
    return st.Topography(z.T * scale, (nx * PIXEL * scale, ny * PIXEL * scale), unit=unit, periodic=periodic)


@pytest.mark.parametrize("unit", ["nm", "um", "mm"])
def test_instrument_netcdf_in_any_unit_gives_si_moments(tmp_path, capsys, surface, unit) -> None:
    z, m0, m2, m4 = surface
    path = tmp_path / f"map_{unit}.nc"
    _periodic_topography(_with_short_wave(z), unit).to_netcdf(str(path))
    assert main(["roughness", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["file_height_unit"] == {"um": "µm"}.get(unit, unit) and out["reader"].startswith("SurfaceTopography")
    assert out["pixel_size"] == pytest.approx([PIXEL, PIXEL], rel=1e-6)
    assert out["cutoff_wavelength"] == pytest.approx(4 * PIXEL, rel=1e-6)
    assert (out["detrending"], out["window"]) == ("mean", "none")
    for key, exact in (("m0", m0), ("m2", m2), ("m4", m4)):
        assert out[key] == pytest.approx(exact, rel=1e-5), key  # float32 sizes in the file
    s = summit_parameters(m0, m2, m4)
    for key in ("sigma", "eta", "beta"):
        assert out[key] == pytest.approx(getattr(s, key), rel=1e-5), key
    assert out["rms_height"] > out["sigma"]


def test_x3p_instrument_file(tmp_path, capsys, surface) -> None:
    """ISO 25178-72 X3P (heights in m, not periodic: plane removed, Hann window)."""
    z, m0, m2, m4 = surface
    path = tmp_path / "map.x3p"
    _periodic_topography(z, "um", periodic=False).to_x3p(str(path))
    assert main(["roughness", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert (out["detrending"], out["window"]) == ("plane", "hann")
    for key, exact in (("m0", m0), ("m2", m2), ("m4", m4)):
        assert out[key] == pytest.approx(exact, rel=0.03), key


def _bad(tmp_path, capsys, args: list[str], *expected: str) -> None:
    assert main(["roughness", *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(("g2tom: error: HEIGHTMAP", "g2tom: error: --")), err
    for text in expected:
        assert text in err, err


def test_bad_topographies(tmp_path, capsys, surface) -> None:
    (tmp_path / "junk.xyz").write_bytes(b"\x00\x01garbage" * 50)
    _bad(tmp_path, capsys, [str(tmp_path / "junk.xyz")], "unreadable", "SurfaceTopography knows no format")
    np.save(tmp_path / "small.npy", surface[0][:6, :6])
    _bad(tmp_path, capsys, [str(tmp_path / "small.npy"), "--pixel-size", "1e-6"], "m4 needs at least 8 x 8")
    np.save(tmp_path / "map.npy", surface[0][:64, :64])
    _bad(tmp_path, capsys, [str(tmp_path / "map.npy")], "no pixel size", "--pixel-size")
    _bad(tmp_path, capsys, [str(tmp_path / "map.npy"), "--pixel-size", "1e-6", "--cutoff", "1e-6"],
         "cutoff wavelength = 1e-06 m is out of range", ">= 2e-06")
    _bad(tmp_path, capsys, [str(tmp_path / "map.npy"), "--pixel-size", "1e-6", "--cutoff", "1e-4"], "<= 1.6e-05")


def test_missing_surface_topography_names_the_install(tmp_path, capsys, monkeypatch) -> None:
    (tmp_path / "scan.x3p").write_bytes(b"PK\x03\x04 not really")
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)  # import fails as if not installed
    _bad(tmp_path, capsys, [str(tmp_path / "scan.x3p")], f"{sys.executable} -m pip install SurfaceTopography",
         "extra 'topography'")
