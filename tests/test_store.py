"""Atomic writes, provenance attributes, staleness checks and the CLI frame."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import xarray as xr

from pipeline import __version__
from pipeline.cli import main
from pipeline.config import load_scenario
from pipeline.store import StaleInputError, atomic_path, read_stage, stage_path, write_dataset


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
    assert json.loads(ds.attrs["parameters"])["oxide"]["n_realizations"] == 8
    assert [p.name for p in tmp_path.iterdir()] == ["contact.nc"]
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_stale_or_missing_input_is_refused(tmp_path, small) -> None:
    with pytest.raises(StaleInputError, match="missing"):
        read_stage(tmp_path, "contact", small)
    write_dataset(_dataset(1.0), tmp_path, "contact", small)
    other = load_scenario("paper", {"roughness.sigma": 1e-5})
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
    assert "roughness.sigma = -2e-05 is out of range: must be > 0 (m)" in err
    assert existing.read_bytes() == b"previous result" and os.stat(existing).st_mtime_ns == stamp
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact.nc"]
    assert main(["contact", "--data-dir", str(tmp_path), "--set", "roughness.sigam=1"]) == 2
    assert "did you mean 'roughness.sigma'" in capsys.readouterr().err
    assert main(["cube", "--data-dir", str(tmp_path), "--workers", "0"]) == 2
    assert "--workers = 0 is out of range" in capsys.readouterr().err
    assert main(["bench", "--data-dir", str(tmp_path), "--only", "contakt"]) == 2
    assert "--only 'contakt' is not a benchmark: must be one of contact, oxide, cube" in capsys.readouterr().err
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
