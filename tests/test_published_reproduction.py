"""The published scenario reproduces the numbers of the code before the spectral period and the
adaptive ensemble existed (main at acf7801), bit for bit, through the stage files."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.compute import ComputeOptions
from pipeline.config import load_scenario
from pipeline.stages import contact, cube, fits, oxide

#: A small published-like case (every override is a key the old code knew too).
OVERRIDES = {"loading.n_delta": 6, "oxide.xi": [0.2, 0.5, 0.8], "oxide.lambda": [1.0, 5.0, 13.0, 23.0],
             "oxide.n_realizations": 8, "oxide.chunk": 3, "cube.chunk": 3, "fits.n_bootstrap": 50}
#: SHA-256 (16 hex digits) of each array as the old code wrote it (same files, same venv).
OLD = {
    "oxide": {"psi": "840de97e6a1707e6", "threshold": "1f1bf8f9174ce6b5", "oxide_fraction": "194b046da1bbcc73"},
    "cube": {"resistance": "3a568f40efd6959b", "n_conducting": "84cafc6e4eb8b735"},
    "fits": {"alpha": "4051913d5b3f7796", "gamma": "3d7562ae0963c4bb", "alpha_ci": "9d4a73f64b7c900f",
             "gamma_ci": "679b7137bb26d2ed", "geometric_mean": "59da208fe810b5de",
             "resistance_quantile": "0bfe50b96db2b53c", "open_probability": "1a0295f4bf5986c5"},
}


def _digest(values: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(values).tobytes()).hexdigest()[:16]


def test_published_numbers_are_unchanged(tmp_path: Path) -> None:
    scenario = load_scenario("published", OVERRIDES)
    assert scenario.oxide.period == "window" and scenario.oxide.ensemble == "fixed"
    options = ComputeOptions(progress=False)
    for stage in (contact, oxide, cube, fits):
        stage.run(scenario, tmp_path, options)
    for name, expected in OLD.items():
        with xr.open_dataset(tmp_path / f"{name}.nc") as ds:
            got = {var: _digest(ds[var].values) for var in expected}
        assert got == expected, name
