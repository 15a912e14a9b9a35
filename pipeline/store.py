"""Stage files: atomic netCDF writes, provenance attributes and staleness checks.

Every stage writes exactly one netCDF4 file ``<data_dir>/<stage>.nc``. The file is first
written to a temporary name in the same directory and then renamed over the target, so an
interrupted or failed run never leaves a half-written dataset and never destroys the
previous one.
"""

from __future__ import annotations

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import xarray as xr

from pipeline import __version__
from pipeline.config import STAGE_UPSTREAM, Scenario
from pipeline.errors import StaleInputError

__all__ = ["StaleInputError", "stage_path", "provenance", "write_dataset", "read_stage", "atomic_path"]


def stage_path(data_dir: str | Path, stage: str) -> Path:
    """Path of a stage's output file, ``<data_dir>/<stage>.nc``."""
    return Path(data_dir) / f"{stage}.nc"


def _attr_value(value: Any) -> Any:
    """Something netCDF can store as an attribute."""
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, (list, tuple)):
        return np.asarray(value)
    return value


def provenance(scenario: Scenario, stage: str) -> dict[str, Any]:
    """Attributes every output carries: scenario, every parameter, version, config hashes."""
    attrs: dict[str, Any] = {
        "title": f"g2tom {stage} stage",
        "Conventions": "CF-1.10",
        "g2tom_version": __version__,
        "stage": stage,
        "scenario": scenario.name,
        "scenario_description": scenario.description,
        "config_hash": scenario.config_hash(stage),
        "scenario_hash": scenario.config_hash(),
        "parameters": json.dumps(scenario.to_dict(), sort_keys=True),
    }
    for upstream in STAGE_UPSTREAM[stage]:
        attrs[f"config_hash_{upstream}"] = scenario.config_hash(upstream)
    for key, value in scenario.flat().items():
        attrs[key] = _attr_value(value)
    return attrs


@contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it over ``target`` on success only."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)  # mkstemp creates 0600; outputs are ordinary files
    try:
        yield tmp_path
        with open(tmp_path, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


def write_dataset(ds: xr.Dataset, data_dir: str | Path, stage: str, scenario: Scenario) -> Path:
    """Attach provenance to ``ds`` and write it atomically to ``<data_dir>/<stage>.nc``.

    Returns
    -------
    Path
        The written file.
    """
    ds = ds.copy()
    ds.attrs.update(provenance(scenario, stage))
    target = stage_path(data_dir, stage)
    with atomic_path(target) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    return target


def read_stage(data_dir: str | Path, stage: str, scenario: Scenario) -> xr.Dataset:
    """Load a stage's output into memory, checking it matches ``scenario``.

    Raises
    ------
    StaleInputError
        If the file is missing or its ``config_hash`` differs from the scenario's.
    """
    path = stage_path(data_dir, stage)
    if not path.is_file():
        raise StaleInputError(f"{path} is missing: run `g2tom {stage}` (or `make {stage}`) first")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        found = ds.attrs.get("config_hash")
        expected = scenario.config_hash(stage)
        if found != expected:
            raise StaleInputError(
                f"{path} was built from a different configuration (config_hash {found}, "
                f"scenario '{scenario.name}' needs {expected}): re-run `g2tom {stage}`"
            )
        return ds.load()
