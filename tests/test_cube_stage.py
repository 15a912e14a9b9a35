"""Stage 3 (the resistance cube) on small synthetic contact and oxide datasets."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr
from scipy.special import erfcinv

from g2tom import store
from g2tom.compute import ComputeOptions
from g2tom.before_work import load_scenario
from g2tom.physics import constriction, oxide_field, point_model, spot_models
from g2tom.physics.interaction import AUTO_METHOD
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.scene import FieldSource
from g2tom.stages import contact, cube
from g2tom.stages import oxide as oxide_stage

N = 13
PITCH = 7.07e-5  # m
XI = [0.2, 0.5, 0.8]
LAMBDAS = [1.0, 4.0]
N_REAL = 7
OPTIONS = ComputeOptions(progress=False)


def _contact(n: int = N, n_delta: int = 4) -> xr.Dataset:
    centres = (np.arange(n) - (n - 1) / 2.0) * PITCH
    r2 = (centres[None, :] ** 2 + centres[:, None] ** 2) / PITCH**2
    widths = np.linspace(1.0, 4.0, n_delta)
    radius = 3e-6 * np.exp(-r2[None] / (2.0 * widths[:, None, None] ** 2))
    force = np.linspace(10.0, 900.0, n_delta)
    return xr.Dataset(
        {
            "spot_radius": (("delta", "y", "x"), radius),
            "spot_area": (("delta", "y", "x"), np.pi * radius**2),
            "force": ("delta", force),
            "force_normalized": ("delta", force / 3.0),
        },
        coords={"delta": np.linspace(40e-6, -60e-6, n_delta), "x": centres, "y": centres},
    )


def _oxide(n: int = N, n_real: int = N_REAL, seed: int = 0) -> xr.Dataset:
    rng = np.random.default_rng(seed)
    k = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n)))
    psi = np.empty((len(LAMBDAS), n_real, n, n), np.float32)
    for i, lam in enumerate(LAMBDAS):
        noise = np.fft.fft2(rng.standard_normal((n_real, n, n)))
        field = np.fft.ifft2(noise * np.exp(-((k * lam) ** 2))).real
        field = (field - field.mean(axis=(1, 2), keepdims=True)) / field.std(axis=(1, 2), keepdims=True)
        psi[i] = field
    thr = (np.sqrt(2.0) * erfcinv(2.0 * np.asarray(XI))).astype(np.float32)
    threshold = np.broadcast_to(thr[:, None, None], (len(XI), len(LAMBDAS), n_real)).copy()
    centres = (np.arange(n) - (n - 1) / 2.0) * PITCH
    return xr.Dataset(
        {
            "psi": (("lambda", "realization", "y", "x"), psi),
            "threshold": (("xi", "lambda", "realization"), threshold),
        },
        coords={"xi": XI, "lambda": LAMBDAS, "realization": np.arange(n_real), "x": centres, "y": centres},
    )


def _scenario(**cube_overrides):
    fixed = {"oxide.ensemble": "fixed", "oxide.n_realizations": N_REAL}
    if cube_overrides.get("weights") == "area":  # the published convention of mean-area spots
        fixed["contact.spots"] = "mean_area"
    compute = {"chunk": "compute.cube_chunk", "method": "compute.interaction_sum"}
    return load_scenario("paper_gt", {**fixed, **{compute.get(k, f"cube.{k}"): v for k, v in cube_overrides.items()}})


@dataclasses.dataclass(frozen=True)
class StoredFields:
    """A field source that serves an oxide dataset's psi and thresholds (synthetic fields)."""

    oxide: xr.Dataset

    @property
    def lambdas(self) -> tuple[float, ...]:
        return tuple(self.oxide["lambda"].values)

    @property
    def xi(self) -> np.ndarray:
        return self.oxide["xi"].values

    def fields(self, index: int, realizations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        psi = self.oxide["psi"].transpose("lambda", "realization", "y", "x").values[index, realizations]
        threshold = self.oxide["threshold"].transpose("xi", "lambda", "realization").values[:, index, realizations]
        return psi, threshold


def _build(scenario, contact, oxide, options=OPTIONS):
    return cube.build(scenario, contact, oxide, options, source=StoredFields(oxide))


@pytest.fixture(scope="module")
def inputs():
    return _contact(), _oxide()


@pytest.fixture(scope="module")
def built(inputs):
    return _build(_scenario(chunk=3), *inputs)


def test_layout_units_and_attrs(built):
    dims = ("xi", "lambda", "delta", "realization")
    for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
        assert built[name].dims == dims
    assert built["resistance"].dtype == np.float64 and built["n_conducting"].dtype == np.int32
    assert built["n_open"].dims == ("xi", "lambda", "delta")
    for name in ("resistance_clean", "resistance_clean_self", "resistance_clean_interaction", "force", "force_normalized"):
        assert built[name].dims == ("delta",)
    for name in list(built.data_vars) + list(built.coords):
        assert "units" in built[name].attrs and "long_name" in built[name].attrs, name
    assert built["resistance"].attrs["units"] == "ohm"
    assert built.attrs["crop_tolerance"] == 1e-6 and built.attrs["method"] == AUTO_METHOD
    assert 0 <= built.attrs["crop_error_measured"] <= built.attrs["crop_tolerance"]
    assert built.attrs["crop_error_bound"] <= built.attrs["crop_tolerance"]
    assert built["crop_cells"].values.min() < N  # the light loads are cropped


def test_every_entry_matches_the_double_sum(inputs, built):
    direct = _build(_scenario(method="direct", crop_tolerance=0.0, chunk=N_REAL), *inputs)
    r, ref = built["resistance"].values, direct["resistance"].values
    assert np.array_equal(np.isinf(r), np.isinf(ref)) and not np.isnan(r).any()
    finite = np.isfinite(ref)
    assert np.max(np.abs(r[finite] / ref[finite] - 1.0)) <= 1e-6
    np.testing.assert_array_equal(built["n_conducting"], direct["n_conducting"])


def test_uncropped_fast_path_within_1e_12(inputs):
    fast = _build(_scenario(crop_tolerance=0.0), *inputs)["resistance"].values
    ref = _build(_scenario(method="direct", crop_tolerance=0.0), *inputs)["resistance"].values
    finite = np.isfinite(ref)
    assert np.max(np.abs(fast[finite] / ref[finite] - 1.0)) <= 1e-12


def test_bit_identical_for_any_chunk_size(inputs, built):
    for chunk in (1, 4, N_REAL):
        other = _build(_scenario(chunk=chunk), *inputs)
        for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
            np.testing.assert_array_equal(other[name].values, built[name].values)


def test_no_oxide_gives_the_clean_value(inputs):
    contact, oxide = inputs
    clean_oxide = oxide.assign(threshold=oxide["threshold"] * 0 + np.float32(1e30))
    ds = _build(_scenario(), contact, clean_oxide)
    expected = ds["resistance_clean"].broadcast_like(ds["resistance"])
    np.testing.assert_allclose(ds["resistance"], expected, rtol=1e-6)
    assert np.all(ds["n_conducting"].values == N * N)


def test_all_oxide_is_open_and_counted(inputs):
    contact, oxide = inputs
    covered = oxide.assign(threshold=oxide["threshold"] * 0 - np.float32(1e30))
    ds = _build(_scenario(), contact, covered)
    for name in ("resistance", "resistance_self", "resistance_interaction"):
        assert np.all(np.isposinf(ds[name].values))
    assert np.all(ds["n_open"].values == N_REAL) and ds.attrs["n_open_total"] == ds["resistance"].size


def test_some_open_circuits_are_kept_as_inf(inputs):
    contact, oxide = inputs
    thr = oxide["threshold"].copy()
    thr[-1, :, :3] = np.float32(-1e30)  # the first three fields fully covered at the largest xi
    ds = _build(_scenario(), contact, oxide.assign(threshold=thr))
    assert np.all(ds["n_open"].values[-1] >= 3)
    assert np.all(np.isposinf(ds["resistance"].values[-1, :, :, :3]))
    assert not np.isnan(ds["resistance"].values).any()


def test_threshold_ties_are_oxide_as_in_the_oxide_stage(inputs):
    """An empirical threshold is one of the field's own float32 values: that cell is oxide."""
    contact, oxide = inputs
    psi = oxide["psi"].values
    threshold = oxide_field.empirical_threshold(psi.reshape(psi.shape[:2] + (-1,)), np.asarray(XI))
    assert threshold.dtype == np.float32
    assert np.all((psi[None] == threshold[..., None, None]).any(axis=(-2, -1)))  # a tie in every field
    ties = oxide.assign(threshold=(("xi", "lambda", "realization"), threshold))
    ds = _build(_scenario(), contact, ties)
    covered = oxide_field.covered_count(np.asarray(XI), N * N)
    expected = N * N - covered[:, None, None, None]  # every cell holds a spot (radius > 0)
    np.testing.assert_array_equal(ds["n_conducting"], np.broadcast_to(expected, ds["n_conducting"].shape))
    fraction = oxide_stage._fraction_block(psi, threshold)  # the oxide stage's own count
    np.testing.assert_array_equal(ds["n_conducting"].isel(delta=0), np.rint(N * N * (1.0 - fraction)))


def test_resistance_scales_with_rho(inputs, built):
    scaled = _build(load_scenario("paper_gt", {"material.rho": 2 * 7.2e-7, "compute.cube_chunk": 3, "oxide.ensemble": "fixed", "oxide.n_realizations": N_REAL}), *inputs)
    np.testing.assert_allclose(scaled["resistance"], 2 * built["resistance"], rtol=1e-14)


def test_resistance_grows_with_xi_on_average(inputs, built):
    assert np.all(np.isfinite(built["resistance"]))
    mean = built["resistance"].mean("realization")
    assert np.all(mean.diff("xi") > 0)


def test_same_cube_on_a_local_distributed_cluster(inputs, built, cluster_address):
    ds = _build(_scenario(chunk=3), *inputs, ComputeOptions(scheduler=cluster_address, progress=False))
    # Workers run single-threaded BLAS; this process may not (the CLI pins it to one thread,
    # where the two agree bit for bit), and a multi-threaded GEMM may round differently.
    np.testing.assert_allclose(ds["resistance"].values, built["resistance"].values, rtol=1e-14)


def test_area_weights_change_only_the_interaction_term(inputs, built):
    area = _build(_scenario(weights="area", chunk=3), *inputs)
    np.testing.assert_array_equal(area["resistance_self"], built["resistance_self"])
    np.testing.assert_array_equal(area["n_conducting"], built["n_conducting"])
    assert not np.allclose(area["resistance_interaction"], built["resistance_interaction"])
    assert area.attrs["interaction_weights"] == "area"


def test_published_scenario_differs_only_in_the_interaction_weights():
    paper, published = load_scenario("paper_gt"), load_scenario("published")
    assert published.cube == dataclasses.replace(paper.cube, weights="area")
    assert published.material == paper.material


def test_run_writes_atomically_and_keeps_the_old_file(tmp_path, inputs, monkeypatch):
    scenario = _scenario(chunk=4)
    contact, oxide = inputs
    store.write_dataset(contact, tmp_path, "contact", scenario)
    store.write_dataset(oxide, tmp_path, "oxide", scenario)
    monkeypatch.setattr(FieldSource, "of", classmethod(lambda cls, s: StoredFields(oxide)))
    path = cube.run(scenario, tmp_path, OPTIONS)
    before = path.read_bytes()
    written = store.read_stage(tmp_path, "cube", scenario)
    assert written["resistance"].shape == (len(XI), len(LAMBDAS), contact.sizes["delta"], N_REAL)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(constriction, "resistance", interrupted)
    with pytest.raises(KeyboardInterrupt):
        cube.run(scenario, tmp_path, OPTIONS)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact.nc", "cube.nc", "oxide.nc"]


def test_mismatched_grids_are_rejected(inputs):
    contact, _ = inputs
    with pytest.raises(ValueError, match="cell centres"):
        _build(_scenario(), contact, _oxide(n=N - 2))


@pytest.fixture(scope="module")
def asperity_inputs(small):
    asperities = dataclasses.replace(small, contact=dataclasses.replace(small.contact, spots="asperities"))
    options = ComputeOptions(progress=False)
    return asperities, contact.build(asperities), oxide_stage.build(asperities, options)


def test_asperity_spots_independent_of_chunks_and_workers(asperity_inputs, cluster_address):
    scenario, contact_ds, oxide_ds = asperity_inputs
    base = cube.build(scenario, contact_ds, oxide_ds)
    for chunk, scheduler in ((1, None), (8, cluster_address)):  # threads, two worker processes
        other_scenario = dataclasses.replace(scenario, compute=dataclasses.replace(scenario.compute, cube_chunk=chunk))
        other = cube.build(other_scenario, contact_ds, oxide_ds, ComputeOptions(progress=False, scheduler=scheduler))
        for name in ("resistance", "n_conducting", "resistance_clean"):
            np.testing.assert_array_equal(other[name].values, base[name].values)


def test_asperity_spots_are_the_drawn_surface(asperity_inputs):
    """Each realization's spots are its drawn asperities: counts and the clean surface by hand."""
    scenario, contact_ds, oxide_ds = asperity_inputs
    built = cube.build(scenario, contact_ds, oxide_ds)
    rough = scenario.roughness
    separation = contact_ds["spot_separation"].values
    n = separation.shape[-1]
    psi, threshold = oxide_ds["psi"].values, oxide_ds["threshold"].values
    for k in (0, 5):
        z = spot_models.heights(scenario.oxide.seed, k, n, rough.sigma)
        radius = spot_models.asperity_radius(z[None], separation, rough.beta)
        for a, z_i in ((0, 0), (2, 1)):
            mask = psi[a, k] < threshold[z_i, a, k]
            expected_count = np.count_nonzero((radius > 0) & mask[None], axis=(1, 2))
            np.testing.assert_array_equal(built["n_conducting"].values[z_i, a, :, k], expected_count)
            spots = SpotGeometry.whole_window(radius, radius, scenario.cell_size)
            ref = constriction.resistance(mask[None], spots, scenario.material.rho, "direct").resistance[0]
            got = built["resistance"].values[z_i, a, :, k]
            finite = np.isfinite(ref)
            np.testing.assert_array_equal(np.isfinite(got), finite)
            assert np.max(np.abs(got[finite] / ref[finite] - 1), initial=0.0) <= scenario.cube.crop_tolerance
    # the clean surface: the mean conductance over the first realizations, open circuits counted
    assert 0.0 < built["clean_open_probability"].values[0] < 1.0  # light load: some surfaces do not touch
    assert np.all(built["clean_open_probability"].values[1:] == 0.0)


def test_asperity_spots_with_the_point_model(asperity_inputs):
    """The point model solves each realization's drawn spots: entries against the dense solve."""
    scenario, contact_ds, oxide_ds = asperity_inputs
    point = dataclasses.replace(scenario, cube=dataclasses.replace(scenario.cube, model="point"))
    built = cube.build(point, contact_ds, oxide_ds)
    rough = scenario.roughness
    separation = contact_ds["spot_separation"].values
    psi, threshold = oxide_ds["psi"].values, oxide_ds["threshold"].values
    k, a, z_i = 3, 1, 1
    radius = spot_models.asperity_radius(
        spot_models.heights(scenario.oxide.seed, k, separation.shape[-1], rough.sigma)[None], separation, rough.beta)
    mask = psi[a, k] < threshold[z_i, a, k]
    dense, _ = point_model.resistance_dense(mask[None], radius, scenario.cell_size, scenario.material.rho)
    got = built["resistance"].values[z_i, a, :, k]
    finite = np.isfinite(dense[0])
    np.testing.assert_array_equal(np.isfinite(got), finite)
    assert np.max(np.abs(got[finite] / dense[0][finite] - 1), initial=0.0) <= 1e-5
