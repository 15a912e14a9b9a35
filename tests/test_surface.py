"""`g2tom surface`: the full field on a measured map — limits, the validation's own solver, oxide,
positions, composites and the refusals before work."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest
import xarray as xr

from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.physics.hertz import hertz_radius
from g2tom.reference import devices, scene, surfaces, window
from g2tom.reference.punch import punch_conductance
from g2tom.surface import surface_resistance
from g2tom.surface.solve import PUNCH_TOLERANCE
from g2tom.surface.windows import choose_positions, valid_corners

PIXEL = 0.5e-6
#: A gold-like pair: E* (Pa), rho* (ohm m), sphere radius R* (m).
E_STAR, RHO, RADIUS = 5e10, 2.2e-8, 1e-3
PAIR = {"material.modulus": E_STAR, "material.rho": RHO, "indenter.radius": RADIUS}
GPU_MISSING = devices.gpu_missing()


def rough_map(n: int = 256, rms: float = 0.2e-6, seed: int = 3) -> np.ndarray:
    """A self-affine map (H 0.8) of n x n pixels of PIXEL, periodic over itself, heights in m."""
    side = n * PIXEL
    rng = np.random.default_rng(seed)
    return surfaces.random_process(n, PIXEL, 0.8, 4 * np.pi / side, np.pi / (4 * PIXEL), rms, rng)


@pytest.fixture(scope="module")
def map_file(tmp_path_factory) -> str:
    path = tmp_path_factory.mktemp("maps") / "rough.npy"
    np.save(path, rough_map())
    return str(path)


def test_flat_map_gives_hertz_and_holm(tmp_path) -> None:
    """A smooth sphere on a flat map: contact area pi a^2 and R = rho* / (2 a) with Hertz's a."""
    np.save(tmp_path / "flat.npy", np.zeros((128, 128)))
    forces = np.array([0.2, 0.6])
    ds = surface_resistance(tmp_path / "flat.npy", forces, overrides=PAIR, pixel_size=PIXEL, at="centre")
    a = hertz_radius(forces, RADIUS, E_STAR)
    assert a.min() / PIXEL > 25  # the disc is resolved
    np.testing.assert_allclose(ds["contact_area"].values[0], np.pi * a**2, rtol=0.03)
    np.testing.assert_allclose(ds["resistance_clean"].values[0], RHO / (2 * a), rtol=0.01)


def test_a_map_of_a_validation_surface_gives_validate_own_answer(tmp_path) -> None:
    """The random-process surface of `g2tom validate`, written as a map and pressed at the same force
    on the same window, gives the validation case's resistance (the same solver) within 1e-6."""
    vset = dataclasses.replace(scene.random_process_set(scene.QUICK, rms=20e-6), deltas=(0.0,))
    n, side = 256, scene.QUICK.side / 2
    pixel = side / n
    rough = scene.rough_sphere(vset, 0, n, side) - surfaces.sphere(n, pixel, vset.radius)
    np.save(tmp_path / "validation.npy", rough)
    force = 12.0  # F' 0.03: a few summits near the axis; Hertz's radius spans 16 pixels
    operator, _, state, used = window.solve_in_window(vset, 0, n, force, side)
    assert used == side
    reference = 1.0 / punch_conductance(operator, state.contact, vset.rho).conductance
    ds = surface_resistance(tmp_path / "validation.npy", force, pixel_size=pixel, at="centre", window=n,
                            detrend="none", overrides={"material.modulus": vset.e_star, "material.rho": vset.rho,
                                                       "indenter.radius": vset.radius})
    assert ds["resistance_clean"].values[0, 0] == pytest.approx(reference, rel=1e-6)
    assert ds["contact_area"].values[0, 0] == pytest.approx(state.contact.sum() * pixel**2, rel=1e-6)


def test_oxide_vanishing_gives_clean_and_more_oxide_more_resistance(map_file) -> None:
    ds = surface_resistance(map_file, [0.05, 0.2], overrides=PAIR, pixel_size=PIXEL, positions=2, fields=2,
                            xi=[1e-9, 0.3, 0.6], correlation_length=[4e-6])
    clean = ds["resistance_clean"].values
    r = ds["resistance"].values[:, 0]  # (xi, position, field, force)
    np.testing.assert_array_equal(r[0], np.broadcast_to(clean[:, None, :], r[0].shape))
    assert np.all(r[1] >= clean[:, None, :]) and np.all(r[2] >= r[1])
    np.testing.assert_allclose(ds["oxide_fraction"].values[1:, 0].mean(axis=(1, 2)), [0.3, 0.6], atol=0.15)


def test_positions_reproducible_and_independent(map_file) -> None:
    inside = np.ones((256, 256), bool)
    valid = valid_corners(inside, 64)
    first, again = (choose_positions(valid, 64, 20, seed=7) for _ in range(2))
    np.testing.assert_array_equal(first.corners, again.corners)
    assert first.capacity == 16 and first.independent.sum() == 16 and not first.independent[16:].any()
    tiles = first.corners[:16]
    # the 16 independent windows share no pixel
    for i in range(16):
        for j in range(i):
            assert np.abs(tiles[i] - tiles[j]).max() >= 64
    other = choose_positions(valid, 64, 4, seed=8)
    assert not np.array_equal(other.corners, first.corners[:4])
    # the dataset's positions and fields do not depend on how many positions are asked for
    few = surface_resistance(map_file, 0.05, overrides=PAIR, pixel_size=PIXEL, positions=1, fields=1, xi=[0.4],
                             correlation_length=[4e-6])
    more = surface_resistance(map_file, 0.05, overrides=PAIR, pixel_size=PIXEL, positions=2, fields=1, xi=[0.4],
                              correlation_length=[4e-6])
    assert few["resistance"].values[..., 0, :, :] == pytest.approx(more["resistance"].values[..., 0, :, :], rel=1e-12)


def test_two_maps_are_their_sum(tmp_path) -> None:
    one, two = rough_map(256, seed=1), rough_map(256, rms=0.1e-6, seed=2)
    for name, z in (("one", one), ("two", two), ("sum", one + two)):
        np.save(tmp_path / f"{name}.npy", z)
    both = surface_resistance([tmp_path / "one.npy", tmp_path / "two.npy"], 0.05, overrides=PAIR, pixel_size=PIXEL,
                              at="centre")
    summed = surface_resistance(tmp_path / "sum.npy", 0.05, overrides=PAIR, pixel_size=PIXEL, at="centre")
    np.testing.assert_array_equal(both["resistance_clean"].values, summed["resistance_clean"].values)
    alone = surface_resistance(tmp_path / "one.npy", 0.05, overrides=PAIR, pixel_size=PIXEL, at="centre")
    assert not np.allclose(alone["resistance_clean"].values, summed["resistance_clean"].values, rtol=1e-3)


def test_windows_only_on_measured_pixels(tmp_path) -> None:
    """A map measured in a disc (a ring of undefined pixels around it): every window lies in the disc."""
    z = rough_map(256)
    y, x = np.mgrid[0:256, 0:256]
    outside = np.hypot(x - 127.5, y - 127.5) > 120
    np.save(tmp_path / "disc.npy", np.where(outside, np.nan, z))
    ds = surface_resistance(tmp_path / "disc.npy", 0.03, overrides=PAIR, pixel_size=PIXEL, positions=3)
    n = ds.attrs["window_pixels"]
    for cx, cy in zip(ds["position_x"].values / PIXEL, ds["position_y"].values / PIXEL):
        r0, c0 = round(cy - (n - 1) / 2), round(cx - (n - 1) / 2)
        assert not outside[r0:r0 + n, c0:c0 + n].any()
    assert np.isfinite(ds["resistance_clean"].values).all()


def test_capped_contact_is_wider_than_elastic(map_file) -> None:
    elastic = surface_resistance(map_file, [0.05, 0.5], overrides=PAIR, pixel_size=PIXEL, at="centre")
    capped = surface_resistance(map_file, [0.05, 0.5], overrides={**PAIR, "material.hardness": 1.5e9},
                                pixel_size=PIXEL, at="centre")
    assert np.all(capped["contact_area"].values > elastic["contact_area"].values)
    assert np.all(capped["resistance_clean"].values < elastic["resistance_clean"].values)
    assert np.all(capped["plastic_share"].values > 0) and "plastic_share" not in elastic


@pytest.mark.parametrize("extra, message", [
    (["--force", "1e-6"], "--force = 1e-06 is out of range: its contact radius"),
    (["--force", "50"], "--force = 50 is out of range: its contact needs a window"),
    (["--force", "0.05", "--xi", "1.2", "--correlation-length", "4e-6"], "--xi = 1.2 is out of range"),
    (["--force", "0.05", "--xi", "0.3", "--correlation-length", "1e-7"], "--correlation-length = 1e-07 is out of range"),
    (["--force", "0.05", "--xi", "0.3"], "--xi is given without --correlation-length"),
    (["--force", "0.05", "--at", "0,0"], "--at = 0,0 is out of range"),
    (["--force", "-1"], "--force = -1 is out of range"),
])
def test_refusals_before_work(tmp_path, map_file, capsys, extra, message) -> None:
    code = main(["surface", map_file, "--pixel-size", str(PIXEL), "--set", f"material.modulus={E_STAR}",
                 "--set", f"indenter.radius={RADIUS}", "--data-dir", str(tmp_path), *extra])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "surface").exists()


def test_all_undefined_map_refused(tmp_path, capsys) -> None:
    np.save(tmp_path / "empty.npy", np.full((64, 64), np.nan))
    code = main(["surface", str(tmp_path / "empty.npy"), "--pixel-size", str(PIXEL), "--force", "0.05",
                 "--data-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("g2tom: error:") and err.count("\n") == 1, err


def test_cli_writes_dataset_csv_and_figure(tmp_path, map_file, capsys) -> None:
    code = main(["surface", map_file, "--pixel-size", str(PIXEL), "--force", "0.03,0.1", "--positions", "2",
                 "--xi", "0.3", "--correlation-length", "4e-6", "--fields", "2", "--set", f"material.modulus={E_STAR}",
                 "--set", f"material.rho={RHO}", "--set", f"indenter.radius={RADIUS}", "--data-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0
    folder = tmp_path / "surface"
    with xr.open_dataset(folder / "surface.nc") as ds:
        for name, var in {**ds.data_vars, **ds.coords}.items():
            assert var.attrs.get("units") and var.attrs.get("long_name"), name
        assert ds.attrs["map_sha256"] and ds.attrs["window_pixels"] > 0
        typical = ds["resistance_clean_typical"].values
    rows = (folder / "surface.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 2 * (1 + 2)
    assert (folder / "surface.png").stat().st_size > 10_000
    report = (folder / "surface.md").read_text()
    assert f"{typical[0]:.4g}" in report and "g2tom surface " in report and "--fields 2" in report
    from g2tom.analysis.report_blocks import Block
    from g2tom.analysis.report_surface import surface_blocks

    blocks = surface_blocks(tmp_path)  # the study's report takes the same section
    assert blocks[0].kind == "h2" and any(b.kind == "table" for b in blocks)
    assert Block("img", blocks[-1].text, src="surface/surface.png") == blocks[-1]
    assert surface_blocks(tmp_path / "elsewhere") == []
    assert f"{typical[0]:.5g}" in out and math.isfinite(typical[1])


def self_affine_pair(n: int = 2048, seed: int = 11) -> tuple[np.ndarray, np.ndarray]:
    """The same self-affine surface (H 0.8, 2.5 decades from roll-off to the short cut-off at 2
    pixels) on n^2 pixels of PIXEL / 2 and on (n/2)^2 pixels of PIXEL without its finest octave."""
    pixel = PIXEL / 2
    q = 2 * np.pi * np.fft.fftfreq(n, d=pixel)
    qq = np.hypot(*np.meshgrid(q, q))
    q_high = np.pi / pixel
    q_roll = q_high / 10**2.5
    spectrum = np.maximum(qq, q_roll) ** (-2 * 1.8)
    spectrum[0, 0] = 0.0
    spectrum[qq > q_high] = 0.0
    rng = np.random.default_rng(seed)
    fine = np.fft.ifft2(np.sqrt(spectrum) * np.exp(2j * np.pi * rng.random((n, n)))).real
    fine *= 0.3e-6 / fine.std()
    lowered = np.fft.fft2(fine)
    lowered[qq > q_high / 2] = 0.0
    return fine, np.fft.ifft2(lowered).real[::2, ::2]


@pytest.mark.stress
def test_halving_the_pixel_moves_summits_not_resistance(tmp_path) -> None:
    """A finer map of the same surface: eta and beta move by more than 2x, the full field's typical R
    over 8 positions (the same windows on both maps) by at most 2 % (measured: -0.87, +0.14, +0.06,
    -0.05 % at 0.02, 0.1, 0.5, 3 N; eta x3.85, beta x0.436). One position alone moves by up to 7.6 %
    at 0.02 N, where a few of the finest summits carry the contact."""
    from g2tom.heightmap import measure

    fine, coarse = self_affine_pair()
    np.save(tmp_path / "fine.npy", fine)
    np.save(tmp_path / "coarse.npy", coarse)
    pair = {"material.modulus": 4.8e10, "material.rho": RHO, "indenter.radius": RADIUS}
    answers, summits = {}, {}
    for name, pixel, n in (("coarse", PIXEL, 256), ("fine", PIXEL / 2, 512)):
        summits[name] = measure(tmp_path / f"{name}.npy", pixel, cutoff=2 * pixel)
        answers[name] = surface_resistance(tmp_path / f"{name}.npy", [0.02, 0.1, 0.5, 3.0], pixel_size=pixel,
                                           window=n, positions=8, overrides=pair)
    assert summits["fine"]["eta"] / summits["coarse"]["eta"] > 2
    assert summits["fine"]["beta"] / summits["coarse"]["beta"] < 0.5
    np.testing.assert_allclose(answers["fine"]["position_x"].values, answers["coarse"]["position_x"].values,
                               atol=PIXEL)
    np.testing.assert_allclose(answers["fine"]["resistance_clean_typical"].values,
                               answers["coarse"]["resistance_clean_typical"].values, rtol=0.02)


def test_statistical_answer_beside_the_full_field(tmp_path, map_file) -> None:
    """The map's summits through the predictor (the shipped atlas): a finite ratio where it answers;
    outside the atlas's scenes, or with a hardness (the atlas is elastic), the reason it does not."""
    side = 512 * PIXEL  # finer content than rough_map's: its summits lie in the atlas's scenes
    np.save(tmp_path / "rougher.npy", surfaces.random_process(512, PIXEL, 0.8, 8 * np.pi / side, np.pi / (2 * PIXEL),
                                                              0.3e-6, np.random.default_rng(5)))
    elastic = surface_resistance(tmp_path / "rougher.npy", [0.05, 0.2], overrides=PAIR, pixel_size=PIXEL, positions=1, fields=2,
                                 xi=[0.3], correlation_length=[20e-6])
    assert "atlas" in elastic.attrs["statistical_answer"]
    ratio = elastic["statistical_ratio"].values
    np.testing.assert_allclose(ratio, elastic["resistance_typical"].values / elastic["resistance_statistical"].values)
    assert np.isfinite(ratio).any() and np.all((ratio[np.isfinite(ratio)] > 0.3) & (ratio[np.isfinite(ratio)] < 3))
    outside = surface_resistance(map_file, 0.05, overrides=PAIR, pixel_size=PIXEL, positions=1, fields=1, xi=[0.3],
                                 correlation_length=[4e-6])
    assert outside.attrs["statistical_answer"].startswith("none: Pi = ")
    capped = surface_resistance(tmp_path / "rougher.npy", 0.05, overrides={**PAIR, "material.hardness": 1.5e9},
                                pixel_size=PIXEL,
                                positions=1, fields=1, xi=[0.3], correlation_length=[4e-6])
    assert capped.attrs["statistical_answer"].startswith("none: material.hardness")
    assert "statistical_ratio" not in capped


def test_spectrum_of_a_map_and_surfaces_drawn_from_it() -> None:
    """The radially averaged spectrum of a self-affine map gives back its variance; surfaces drawn
    from it (one period of the map's size) have the map's variance and spectrum across the band."""
    from g2tom.physics.spectrum_synthesis import isotropic_spectrum, synthesize

    z = rough_map(256, rms=0.3e-6)
    inside = np.ones(z.shape, bool)
    spectrum = isotropic_spectrum(z, inside, PIXEL)
    drawn = [synthesize(spectrum, 256, PIXEL, np.random.default_rng(k), period=256) for k in range(8)]
    assert np.mean([d.std() for d in drawn]) == pytest.approx(z.std(), rel=0.1)
    again = isotropic_spectrum(drawn[0], inside, PIXEL)
    middle = slice(len(spectrum.q) // 4, 3 * len(spectrum.q) // 4)  # the band away from its ends
    ratio = np.exp(np.mean(np.log(again.power[middle] / spectrum.power[middle])))
    assert ratio == pytest.approx(1.0, rel=0.15)
    assert spectrum(np.array([spectrum.q_min / 10]))[0] == pytest.approx(spectrum.power[0])  # the plateau
    assert spectrum(np.array([2 * spectrum.q_max]))[0] == 0.0


def test_a_map_smaller_than_the_window_is_extended_from_its_spectrum(tmp_path) -> None:
    np.save(tmp_path / "small.npy", rough_map(128, rms=0.2e-6))
    args = dict(overrides=PAIR, pixel_size=PIXEL, positions=3, extend="spectrum")
    ds = surface_resistance(tmp_path / "small.npy", [0.03, 0.1], **args)
    assert ds.attrs["window_pixels"] > 128 and "drawn from the map's isotropic power spectrum" in ds.attrs["extended"]
    assert np.isnan(ds["position_x"].values).all() and np.isfinite(ds["resistance_clean"].values).all()
    again = surface_resistance(tmp_path / "small.npy", [0.03, 0.1], **args)
    np.testing.assert_array_equal(again["resistance_clean"].values, ds["resistance_clean"].values)
    with pytest.raises(ConfigError, match="^force = 0.1 is out of range: its contact needs a window"):
        surface_resistance(tmp_path / "small.npy", [0.03, 0.1], overrides=PAIR, pixel_size=PIXEL)


def test_plan_prints_the_work_and_writes_nothing(tmp_path, map_file, capsys) -> None:
    code = main(["surface", map_file, "--pixel-size", str(PIXEL), "--force", "0.03,0.1", "--positions", "3",
                 "--xi", "0.3", "--correlation-length", "4e-6", "--fields", "2", "--set", f"material.modulus={E_STAR}",
                 "--set", f"indenter.radius={RADIUS}", "--data-dir", str(tmp_path), "--plan", "--workers", "1"])
    out = capsys.readouterr().out
    assert code == 0 and not (tmp_path / "surface").exists()
    assert "6 contact solves, 18 conductances" in out and "on 1 core(s)" in out and "MiB a task" in out


def test_oblong_pixels_are_resampled_onto_square_ones(tmp_path) -> None:
    """A map with pixels twice as long along y, written as an instrument file, is resampled along x
    onto the coarser pitch: the same answer as the map sampled at that pitch, within 2 %."""
    st = pytest.importorskip("SurfaceTopography")
    z = rough_map(512, rms=0.2e-6)
    oblong = z[::2, :]  # rows every 2 pixels: dy = 2 PIXEL, dx = PIXEL
    topography = st.Topography(oblong.T.copy(), (512 * PIXEL, 256 * 2 * PIXEL), unit="m", periodic=False)
    topography.to_x3p(str(tmp_path / "oblong.x3p"))
    np.save(tmp_path / "square.npy", z[::2, ::2])
    oblong_answer = surface_resistance(tmp_path / "oblong.x3p", 0.1, overrides=PAIR, at="centre")
    square_answer = surface_resistance(tmp_path / "square.npy", 0.1, overrides=PAIR, pixel_size=2 * PIXEL, at="centre")
    assert "resampled linearly" in oblong_answer.attrs["map_resampled"]
    assert oblong_answer.attrs["map_pixel_size"] == pytest.approx(2 * PIXEL)
    np.testing.assert_allclose(oblong_answer["resistance_clean"].values, square_answer["resistance_clean"].values,
                               rtol=0.02)


def test_a_force_the_window_cannot_carry_below_the_hardness_is_marked_not_raised(map_file) -> None:
    """A window whose whole area at H carries less than the force: that force is NaN, the others solved."""
    window = 64
    too_much = 1.5e9 * (window * PIXEL) ** 2 * 1.5
    ds = surface_resistance(map_file, [0.02, too_much], overrides={**PAIR, "material.hardness": 1.5e9},
                            pixel_size=PIXEL, at="centre", window=window)
    assert ds["solved"].values.tolist() == [[1, 0]]
    assert np.isfinite(ds["resistance_clean"].values[0, 0]) and np.isnan(ds["resistance_clean"].values[0, 1])


def test_default_positions_are_the_independent_windows_the_map_holds(tmp_path) -> None:
    """Without --positions: every window that shares no pixel with another, at most 16; a map that holds
    one gives one, not a refusal."""
    np.save(tmp_path / "one.npy", rough_map(256, rms=0.2e-6))
    ds = surface_resistance(tmp_path / "one.npy", 0.1, overrides=PAIR, pixel_size=PIXEL)
    assert ds.sizes["position"] == ds.attrs["independent_positions"] == 1


@pytest.mark.parametrize("name, heights, message", [
    ("str", np.array([["a"] * 4] * 4), "heights must be real numbers"),
    ("complex", np.ones((64, 64)) * (1 + 1j), "complex-valued"),
    ("inf", np.where(np.eye(64, dtype=bool), np.inf, 0.0), "non-finite"),
    ("line", np.ones(64), "must be a 2-D array"),
])
def test_maps_that_are_not_height_maps_are_refused(tmp_path, capsys, name, heights, message) -> None:
    np.save(tmp_path / f"{name}.npy", heights)
    code = main(["surface", str(tmp_path / f"{name}.npy"), "--pixel-size", str(PIXEL), "--force", "0.05",
                 "--data-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err
    assert not (tmp_path / "surface").exists()


def test_device_gpu_without_one_is_refused_before_work(tmp_path, map_file, capsys, monkeypatch) -> None:
    monkeypatch.setattr(devices, "gpu_missing", lambda: "CuPy is not installed")
    code = main(["surface", map_file, "--pixel-size", str(PIXEL), "--force", "0.05", "--device", "gpu",
                 "--data-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and err == "g2tom: error: --device gpu cannot be used: CuPy is not installed\n", err
    assert not (tmp_path / "surface").exists()
    with pytest.raises(ConfigError, match="^device 'tpu' is not allowed"):
        surface_resistance(map_file, 0.05, overrides=PAIR, pixel_size=PIXEL, device="tpu")


def test_device_gpu_builds_every_position_on_the_gpu_namespace(map_file, monkeypatch) -> None:
    """The GPU path's wiring, on any machine: every position's operator asks for the ``gpu`` namespace
    (NumPy stands in for CuPy here, so the answer equals the CPU's exactly) and one at a time."""
    asked = []

    def namespace(device: str):
        asked.append(device)
        return np

    kwargs = dict(overrides=PAIR, pixel_size=PIXEL, positions=2, fields=1, xi=[0.3], correlation_length=[4e-6])
    on_cpu = surface_resistance(map_file, [0.05, 0.2], **kwargs)
    assert set(asked) <= {"cpu"}
    monkeypatch.setattr(devices, "gpu_missing", lambda: None)
    monkeypatch.setattr(devices, "namespace", namespace)
    asked.clear()
    on_gpu = surface_resistance(map_file, [0.05, 0.2], device="gpu", **kwargs)
    assert asked == ["gpu", "gpu"] and on_gpu.attrs["device"] == "gpu" and on_cpu.attrs["device"] == "cpu"
    for name in ("resistance_clean", "resistance", "contact_area"):
        np.testing.assert_array_equal(on_gpu[name].values, on_cpu[name].values)


@pytest.mark.gpu
@pytest.mark.skipif(GPU_MISSING is not None, reason=f"no GPU to test on: {GPU_MISSING}")
@pytest.mark.parametrize("hardness", [None, 1e9])
def test_gpu_positions_equal_the_cpu(map_file, hardness) -> None:
    """The same positions on CuPy and on NumPy, elastic and capped. The FFTs round differently, so the
    conjugate gradients stop at different iterates inside their tolerances: R agrees within the punch's
    relative residual (1e-5; 3.1e-6 measured on an H200), the contact areas within a few rim pixels."""
    kwargs = dict(overrides={**PAIR, "material.hardness": hardness or "none"}, pixel_size=PIXEL, positions=2,
                  fields=2, xi=[0.3], correlation_length=[4e-6])
    on_gpu, on_cpu = (surface_resistance(map_file, [0.05, 0.2], device=d, **kwargs) for d in ("gpu", "cpu"))
    assert on_gpu.attrs["device"] == "gpu"
    assert ("plastic_share" in on_cpu) == (hardness is not None)
    tolerances = {"resistance_clean": PUNCH_TOLERANCE, "resistance": PUNCH_TOLERANCE, "contact_area": 1e-3,
                  "plastic_share": 1e-3}
    differences = {name: float(np.max(np.abs(on_gpu[name].values / on_cpu[name].values - 1)))
                   for name in tolerances if name in on_cpu}
    assert all(differences[name] <= tolerances[name] for name in differences), differences


def test_the_gpu_benchmark_says_when_there_is_no_gpu(monkeypatch) -> None:
    from g2tom.bench import surface_gpu

    monkeypatch.setattr(devices, "gpu_missing", lambda: "CuPy is not installed")
    assert surface_gpu.run(None) == {"skipped": "no GPU: CuPy is not installed"}


@pytest.mark.parametrize("window, measured", [(256, 2.14), (512, 2.20), (1024, 5.12)])
def test_the_gpu_plan_of_a_position_is_within_one_and_a_half_of_the_h200s(window, measured) -> None:
    """One position of make bench's surface_gpu case (10 forces, 8 oxide fields), measured on an H200 (2026-11-29)."""
    from g2tom.before_work import load_scenario
    from g2tom.bench.surface import CASE, PAIR
    from g2tom.surface.run import Prepared, estimate
    from g2tom.surface.study import study_of
    from g2tom.surface.windows import Positions

    study = study_of(load_scenario("paper", PAIR, rough_scene=False), CASE["forces"], xi=CASE["xi"],
                     correlation_lengths=CASE["correlation_length"], fields=CASE["fields"])
    prepared = Prepared(study, None, window, Positions(np.zeros((1, 2), int), np.ones(1, bool), 1), None)
    assert 1 / 1.5 < estimate(prepared, 1, "gpu")[0] / measured < 1.5


def test_the_study_checks_do_not_refuse_a_surface(tmp_path, map_file, capsys) -> None:
    """`g2tom surface` uses the scenario's materials, indenter and oxide spectrum, not its study: a
    roughness or worker count the study's stages could not hold is no reason to refuse it."""
    code = main(["surface", map_file, "--pixel-size", str(PIXEL), "--force", "0.05", "--set", f"material.modulus={E_STAR}",
                 "--set", f"indenter.radius={RADIUS}", "--set", "roughness.eta=1e20", "--workers", "100000",
                 "--data-dir", str(tmp_path), "--plan"])
    captured = capsys.readouterr()
    assert code == 0 and "stage" not in captured.err, captured.err
    assert "surface: window" in captured.out


@pytest.mark.parametrize("change, named", [
    ({"maps": 42}, "maps = 42"), ({"maps": []}, "maps = []"), ({"force": "5N"}, "force = '5N'"),
    ({"pixel_size": "5e-7"}, "pixel_size = '5e-7'"), ({"fields": 2.5}, "fields = 2.5"), ({"window": 10.5}, "window = 10.5"),
    ({"at": (1.0,)}, "at = (1.0,)"), ({"at": "middle"}, "at = 'middle'"), ({"overrides": [1, 2]}, "overrides = [1, 2]"),
    ({"data_dir": None}, "data_dir = None"), ({"options": "fast"}, "options = 'fast'"),
    ({"xi": "0.3", "correlation_length": 5e-6}, "xi = '0.3'"),
])
def test_the_python_api_names_a_wrong_argument(map_file, change, named) -> None:
    arguments = {"maps": map_file, "force": 0.05, "pixel_size": PIXEL, "overrides": PAIR, **change}
    with pytest.raises(ConfigError, match=re.escape(named) + " is not allowed"):
        surface_resistance(**arguments)


@pytest.mark.parametrize("change, python, command_line", [
    ({"positions": 5000}, "positions = 5000 is out of range: must be in [1, 4096]", ["--positions", "5000"]),
    ({"xi": 0.3, "correlation_length": 1e-9}, "correlation_length = 1e-09 is out of range",
     ["--xi", "0.3", "--correlation-length", "1e-9"]),
    ({"extend": "spectrum", "at": "centre"}, "extend = 'spectrum' is not allowed with at:",
     ["--extend", "spectrum", "--at", "centre"]),
])
def test_the_checks_shared_with_the_command_line_name_the_python_arguments(tmp_path, map_file, capsys, change, python,
                                                                             command_line) -> None:
    """A refusal from the checks `g2tom surface` shares names ``positions``, ``correlation_length`` in
    Python and ``--positions``, ``--correlation-length`` on the command line."""
    with pytest.raises(ConfigError, match="^" + re.escape(python)):
        surface_resistance(map_file, 0.05, overrides=PAIR, pixel_size=PIXEL, **change)
    code = main(["surface", map_file, "--pixel-size", str(PIXEL), "--force", "0.05", "--set", f"material.modulus={E_STAR}",
                 "--set", f"indenter.radius={RADIUS}", *command_line, "--data-dir", str(tmp_path)])
    flag = python.split(" ", 1)[0].replace("_", "-")
    assert code == 2 and capsys.readouterr().err.startswith(f"g2tom: error: --{flag} = "), flag


def test_python_terms_keep_the_commands_to_run() -> None:
    from g2tom.config.arguments import python_terms

    assert python_terms("--pixel-size = 5 is out of range; give --window <= 8 or run `g2tom surface --plan --at x`"
                        " (a-- b --)") == ("pixel_size = 5 is out of range; give window <= 8 or run "
                                           "`g2tom surface --plan --at x` (a-- b --)")
