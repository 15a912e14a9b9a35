"""Atomic writes, provenance attributes, staleness checks and the CLI frame."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import xarray as xr

from g2tom import __version__
from g2tom.cli.main import main
from g2tom.before_work import load_scenario
from g2tom.store import StaleInputError, atomic_path, read_stage, stage_path, stage_problem, write_dataset
from tests.conftest import SMALL_ARGS, SMALL_OVERRIDES


def _dataset(value: float) -> xr.Dataset:
    return xr.Dataset(
        {"v": ("delta", np.full(3, value), {"units": "1", "long_name": "test value"})},
        coords={"delta": ("delta", np.arange(3.0), {"units": "m", "long_name": "approach"})},
    )


def test_write_records_provenance_and_reads_back(tmp_path, small) -> None:
    path = write_dataset(_dataset(1.0), tmp_path, "contact", small)
    assert path == stage_path(tmp_path, "contact")
    ds = read_stage(tmp_path, "contact", small)
    assert ds.attrs["g2tom_version"] == __version__
    assert ds.attrs["config_hash"] == small.config_hash("contact")
    assert ds.attrs["roughness.sigma"] == small.roughness.sigma
    assert json.loads(ds.attrs["parameters"])["contact.n_radial"] == 160
    assert ds.attrs["history"].endswith("stage contact, scenario paper_gt")
    assert f"g2tom {__version__}" in ds.attrs["history"]
    assert [p.name for p in tmp_path.iterdir()] == ["contact.nc"]
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_stale_or_missing_input_is_refused(tmp_path, small) -> None:
    with pytest.raises(StaleInputError, match="missing"):
        read_stage(tmp_path, "contact", small)
    write_dataset(_dataset(1.0), tmp_path, "contact", small)
    other = load_scenario("paper_gt", {"roughness.sigma": 1e-5})
    with pytest.raises(StaleInputError, match="different configuration"):
        read_stage(tmp_path, "contact", other)


def test_failed_write_keeps_previous_file_and_leaves_no_temporary(tmp_path, small) -> None:
    write_dataset(_dataset(1.0), tmp_path, "contact", small)
    before = stage_path(tmp_path, "contact").read_bytes()
    with pytest.raises(RuntimeError, match="interrupted"):
        with atomic_path(stage_path(tmp_path, "contact")) as tmp:
            tmp.write_bytes(b"half a dataset")
            raise RuntimeError("interrupted")
    assert stage_path(tmp_path, "contact").read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["contact.nc"]


def test_unwritable_dataset_leaves_no_trace(tmp_path, small) -> None:
    bad = xr.Dataset({"v": ("x", np.array([object()], dtype=object))})
    with pytest.raises(Exception):
        write_dataset(bad, tmp_path, "contact", small)
    assert list(tmp_path.iterdir()) == []


def test_cli_rejects_bad_input_with_status_2_and_touches_nothing(tmp_path, capsys) -> None:
    existing = tmp_path / "contact.nc"
    existing.write_bytes(b"previous result")
    stamp = os.stat(existing).st_mtime_ns
    status = main(["contact", "--data-dir", str(tmp_path), "--set", "roughness.sigma=-2e-5"])
    assert status == 2
    err = capsys.readouterr().err
    assert "roughness.sigma = -2e-05 is out of range: must be > 0 and <= 1 (m)" in err
    assert existing.read_bytes() == b"previous result" and os.stat(existing).st_mtime_ns == stamp
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact.nc"]
    assert main(["contact", "--data-dir", str(tmp_path), "--set", "roughness.sigam=1"]) == 2
    assert "did you mean 'roughness.sigma'" in capsys.readouterr().err
    assert main(["cube", "--data-dir", str(tmp_path), "--workers", "0"]) == 2
    assert "--workers = 0 is out of range" in capsys.readouterr().err
    assert main(["bench", "--data-dir", str(tmp_path), "--only", "contakt"]) == 2
    from g2tom.bench import BENCHMARKS

    assert f"--only 'contakt' is not a benchmark: must be one of {', '.join(BENCHMARKS)}" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact.nc"]


def test_stamps_change_only_with_their_stage_parameters(tmp_path) -> None:
    assert main(["stamp", "--data-dir", str(tmp_path)]) == 0
    stamps = tmp_path / ".stamps"
    before = {p.name: p.stat().st_mtime_ns for p in stamps.iterdir()}
    assert set(before) == {f"{s}.json" for s in ("contact", "oxide", "cube", "fits", "surrogate")}
    assert main(["stamp", "--data-dir", str(tmp_path)]) == 0
    assert {p.name: p.stat().st_mtime_ns for p in stamps.iterdir()} == before
    assert main(["stamp", "--data-dir", str(tmp_path), "--set", "fits.min_force=100"]) == 0
    after = {p.name: p.stat().st_mtime_ns for p in stamps.iterdir()}
    changed = {name for name in before if after[name] != before[name]}
    assert changed == {"cube.json", "fits.json", "surrogate.json"}  # the cube's stopping rule fits F >= min_force


def test_only_the_parameters_that_shaped_a_file_are_recorded(tmp_path, small) -> None:
    for stage in ("oxide", "cube"):
        write_dataset(_dataset(1.0), tmp_path, stage, small)
    with xr.open_dataset(stage_path(tmp_path, "oxide")) as ox, xr.open_dataset(stage_path(tmp_path, "cube")) as cu:
        assert "material.rho" not in ox.attrs and "fits.seed" not in ox.attrs
        assert ox.attrs["oxide.n_realizations"] == 8 and ox.attrs["roughness.eta"] == small.roughness.eta
        oxide_params = json.loads(ox.attrs["parameters"])
        assert set(oxide_params) == set(small.stage_parameters("oxide"))
        # the cube is shaped by its own, the contact and the oxide parameters, not by the fits
        cube_params = json.loads(cu.attrs["parameters"])
        assert cube_params["material.rho"] == small.material.rho
        assert cube_params["oxide.seed"] == small.oxide.seed
        assert cube_params["contact.n_radial"] == 160
        # the adaptive ensemble's stopping rule
        rule = {"fits.min_force", "fits.fit_range", "fits.min_force_normalized", "fits.confidence"}
        assert not any(k.startswith(("fits.", "surrogate.")) and k not in rule for k in cube_params)
        assert cu.attrs["config_hash_oxide"] == small.config_hash("oxide")


def test_truncated_stage_file_names_file_and_fix(tmp_path, small) -> None:
    path = write_dataset(_dataset(1.0), tmp_path, "contact", small)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    problem = stage_problem(tmp_path, "contact", small)
    assert problem.startswith(f"{path} is unreadable (") and "`g2tom contact`" in problem
    assert "\n" not in problem
    with pytest.raises(StaleInputError, match="unreadable"):
        read_stage(tmp_path, "contact", small)
    path.write_bytes(b"")
    assert "unreadable" in stage_problem(tmp_path, "contact", small)


def test_stamp_touches_a_damaged_or_foreign_stage_file(tmp_path, small) -> None:
    args = ["--data-dir", str(tmp_path), *SMALL_ARGS]
    assert main(["stamp", *args]) == 0
    stamps = tmp_path / ".stamps"
    write_dataset(_dataset(1.0), tmp_path, "fits", small)
    os.utime(stamps / "fits.json", ns=(1, 1))
    assert main(["stamp", *args]) == 0  # a current fits.nc: the stamp is left alone
    assert (stamps / "fits.json").stat().st_mtime_ns == 1
    other = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.seed": 8})
    write_dataset(_dataset(1.0), tmp_path, "fits", other)
    assert main(["stamp", *args]) == 0  # built with fits.seed = 8: make must rebuild it
    assert (stamps / "fits.json").stat().st_mtime_ns > stage_path(tmp_path, "fits").stat().st_mtime_ns - 1
    assert (stamps / "fits.json").stat().st_mtime_ns > 1
    os.utime(stamps / "cube.json", ns=(1, 1))
    (tmp_path / "cube.nc").write_bytes(b"CDF\x01 truncated")
    assert main(["stamp", *args]) == 0
    assert (stamps / "cube.json").stat().st_mtime_ns > 1


def test_unconverged_contact_is_refused_by_later_stages_unless_allowed(tmp_path, small) -> None:
    ds = _dataset(1.0).assign_coords(delta_sigma=("delta", [2.0, 0.0, -3.0], {"units": "1", "long_name": "d"}))
    ds["converged"] = ("delta", np.array([1, 0, 1], np.int8), {"units": "1", "long_name": "ok"})
    ds["residual"] = ("delta", np.array([1e-12, 3e-4, 1e-12]), {"units": "1", "long_name": "res"})
    write_dataset(ds, tmp_path, "contact", small)
    with pytest.raises(StaleInputError, match=r"did not converge at delta/sigma = 0 .*residual 0.0003.*max_iterations"):
        read_stage(tmp_path, "contact", small)
    assert read_stage(tmp_path, "contact", small, allow_unconverged=True)["converged"].sum() == 2
