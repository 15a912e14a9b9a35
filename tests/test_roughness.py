"""Roughness parameters from height maps (Sect. 3.2) and `g2tom roughness`."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from g2tom.cli.main import main
from tests.oracles import roughness_parameters

PIXEL = 1e-6  # m


def wave_surface(n: int = 256, seed: int = 0) -> tuple[np.ndarray, float, float, float]:
    """Sum of plane waves with integer periods on the map, random directions and phases.

    Returns the map (m) and the exact m0, m2, m4 of the continuous surface.
    """
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:n, 0:n] * PIXEL
    z = np.zeros((n, n))
    m0 = m2 = m4 = 0.0
    periods = [(6, 1), (-3, 5), (2, -7), (8, 3), (-5, -4), (1, 9), (7, -6), (-9, 2)]
    for kx_i, ky_i in periods:  # 6-11 periods over 256 px: >= 23 px per wavelength
        amp = 1e-6 * rng.uniform(0.5, 1.5)
        kx, ky = 2 * np.pi * kx_i / (n * PIXEL), 2 * np.pi * ky_i / (n * PIXEL)
        z += amp * np.cos(kx * x + ky * y + rng.uniform(0, 2 * np.pi))
        k2 = kx**2 + ky**2
        m0 += amp**2 / 2
        m2 += amp**2 * k2 / 4  # <(dz/dx)^2> averaged over directions
        m4 += 3 * amp**2 * k2**2 / 16
    return z, m0, m2, m4


def test_recovers_moments_of_known_spectrum() -> None:
    z, m0, m2, m4 = wave_surface()
    r = roughness_parameters(z + 3e-6 + 1e-3 * np.arange(z.shape[1]) * PIXEL, PIXEL)  # offset + tilt
    assert r.sigma == pytest.approx(np.sqrt(m0), rel=0.01)
    assert r.m2 == pytest.approx(m2, rel=0.03)
    assert r.m4 == pytest.approx(m4, rel=0.03)
    assert r.eta == pytest.approx(np.sqrt(3) / (18 * np.pi) * m4 / m2, rel=0.05)
    assert r.beta == pytest.approx(0.737 / np.sqrt(m4), rel=0.02)


def test_pixel_size_scaling() -> None:
    z, *_ = wave_surface()
    a, b = roughness_parameters(z, PIXEL), roughness_parameters(z, 2 * PIXEL)
    assert b.m2 == pytest.approx(a.m2 / 4) and b.m4 == pytest.approx(a.m4 / 16)


@pytest.mark.parametrize("suffix", [".npy", ".txt", ".nc"])
def test_cli_reads_every_format(tmp_path, capsys, suffix: str) -> None:
    z, m0, *_ = wave_surface(64)
    path = tmp_path / f"map{suffix}"
    if suffix == ".npy":
        np.save(path, z)
    elif suffix == ".txt":
        np.savetxt(path, z)
    else:
        xr.Dataset({"height": (("y", "x"), z)}).to_netcdf(path)
    assert main(["roughness", str(path), "--pixel-size", str(PIXEL)]) == 0
    out = capsys.readouterr().out
    assert "sigma" in out and "eta" in out and "beta" in out
    rms = float(out.split("rms_height =")[1].split()[0])
    assert rms == pytest.approx(np.sqrt(m0), rel=0.05)
    alpha = float(out.split("alpha =")[1].split()[0])
    sigma = float(out.split("sigma =")[1].split()[0])  # the summits' std, below the surface's
    assert sigma == pytest.approx(np.sqrt(1 - 0.8968 / alpha) * rms, rel=0.05)


def test_cli_bad_input(tmp_path, capsys) -> None:
    z, *_ = wave_surface(32)
    good = tmp_path / "map.npy"
    np.save(good, z)
    cases = {
        "pixel-size": [str(good), "--pixel-size", "0"],
        "does not exist": [str(tmp_path / "missing.npy"), "--pixel-size", "1e-6"],
    }
    np.save(tmp_path / "flat.npy", np.full((16, 16), 2e-6))
    cases["flat"] = [str(tmp_path / "flat.npy"), "--pixel-size", "1e-6"]
    np.save(tmp_path / "line.npy", np.arange(10.0))
    cases["2-D"] = [str(tmp_path / "line.npy"), "--pixel-size", "1e-6"]
    (tmp_path / "junk.txt").write_text("1 2 x\n3 4\n")
    cases["unreadable"] = [str(tmp_path / "junk.txt"), "--pixel-size", "1e-6"]
    for expected, args in cases.items():
        assert main(["roughness", *args]) == 2
        assert expected in capsys.readouterr().err
