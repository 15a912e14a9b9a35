"""The published scenario's numbers do not change: a small published-like case through the stage
files, compared with reference values stored in ``tests/fixtures/published_reference.npz``.

The references were written by the code that recorded the round-1 SHA-256 digests (main at
3bcd5cd, whose stage files matched the digests of main at acf7801 bit for bit). They are
compared with tolerances, not by hashing bytes: BLAS and SIMD kernels (AVX2 against AVX-512,
OpenBLAS's Haswell against SkylakeX kernels) round differently, which moved the cube's values by
up to 5.3e-15 relative on an AVX2 machine while every one of them was right.

Tolerances, and why:

- ``RTOL_FLOAT64 = 1e-12`` for the cube and the fits: a thousand times the cross-processor
  rounding seen (5.3e-15), a hundred times below the smallest change a real edit makes (a
  different interpolation of A* moves alpha by 2.5 %, cropping at the 1e-6 tolerance moves R by
  up to 1e-6). A perturbation of one cube entry by 1e-10 relative fails it
  (:func:`test_a_perturbed_entry_fails`).
- ``RTOL_FIELD = 1e-6`` for the float32 oxide fields: a few float32 ulps (6e-8) of rounding room
  in the two GEMMs that synthesize them, while any change of seed, spectrum or normalisation
  moves them by O(1).
- Integers (spot counts) and the open-circuit pattern (+inf) are compared exactly.

Regenerate the fixture only for a deliberate change of the published numbers:
``python -m tests.test_published_reproduction --write`` (and say why in the commit).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.before_work import load_scenario
from g2tom.stages import contact, cube, fits, oxide

#: A small published-like case (every override is a key the round-1 code knew too).
OVERRIDES = {"loading.n_delta": 6, "oxide.xi": [0.2, 0.5, 0.8], "oxide.lambda": [1.0, 5.0, 13.0, 23.0],
             "oxide.n_realizations": 8, "oxide.chunk": 3, "cube.chunk": 3, "fits.n_bootstrap": 50}
#: The checked variables of each stage file.
CHECKED = {
    "oxide": ("psi", "threshold", "oxide_fraction"),
    "cube": ("resistance", "n_conducting"),
    "fits": ("alpha", "gamma", "alpha_ci", "gamma_ci", "geometric_mean", "resistance_quantile",
             "open_probability"),
}
FIXTURE = Path(__file__).parent / "fixtures" / "published_reference.npz"
RTOL_FLOAT64 = 1e-12
#: The fields are kept at every third cell in y and x (46 kB instead of 400 kB): a field's values
#: are all made by the same two GEMMs, and every cell's mask enters the cube's resistances.
PSI_STRIDE = 3
RTOL_FIELD = 1e-6


def _run_case(directory: Path) -> dict[str, np.ndarray]:
    """Run the case's four stages into ``directory``; the checked arrays keyed ``stage/variable``."""
    scenario = load_scenario("published", OVERRIDES)
    assert scenario.oxide.period == "window" and scenario.oxide.ensemble == "fixed"
    options = ComputeOptions(progress=False)
    for stage in (contact, oxide, cube, fits):
        stage.run(scenario, directory, options)
    out = {}
    for name, variables in CHECKED.items():
        with xr.open_dataset(directory / f"{name}.nc") as ds:
            out.update({f"{name}/{var}": ds[var].values for var in variables})
    out["oxide/psi"] = out["oxide/psi"][..., ::PSI_STRIDE, ::PSI_STRIDE]
    return out


def mismatches(got: dict[str, np.ndarray], expected: dict[str, np.ndarray]) -> list[str]:
    """The checked arrays of ``got`` that differ from ``expected`` beyond the stated tolerances."""
    bad = []
    for key, ref in expected.items():
        value = got[key]
        if value.shape != ref.shape or value.dtype != ref.dtype:
            bad.append(f"{key}: shape/dtype {value.shape} {value.dtype}, expected {ref.shape} {ref.dtype}")
        elif not np.issubdtype(ref.dtype, np.floating):
            if not np.array_equal(value, ref):
                bad.append(f"{key}: {int(np.sum(value != ref))} integer entries differ")
        else:
            rtol = RTOL_FIELD if ref.dtype == np.float32 else RTOL_FLOAT64
            if not np.allclose(value, ref, rtol=rtol, atol=0.0, equal_nan=True):
                with np.errstate(invalid="ignore", divide="ignore"):
                    worst = np.nanmax(np.where(np.isfinite(ref), np.abs(value / ref - 1.0), 0.0))
                bad.append(f"{key}: differs beyond rtol {rtol:g} (largest relative difference {worst:.3g}, "
                           f"or a changed inf/NaN pattern)")
    return bad


@pytest.fixture(scope="module")
def published_case(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    return _run_case(tmp_path_factory.mktemp("published"))


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    with np.load(FIXTURE) as stored:
        return {key: stored[key] for key in stored.files}


def test_published_numbers_are_unchanged(published_case: dict, reference: dict) -> None:
    assert set(reference) == {f"{s}/{v}" for s, vs in CHECKED.items() for v in vs}
    assert mismatches(published_case, reference) == []


def test_a_perturbed_entry_fails(published_case: dict, reference: dict) -> None:
    """The check is tight: one cube entry moved by 1e-10 relative is caught, cross-machine rounding is not."""
    rounding = {k: v.copy() for k, v in published_case.items()}
    r = rounding["cube/resistance"]
    finite = np.flatnonzero(np.isfinite(r))
    assert finite.size > 500
    r.flat[finite] *= 1.0 + 5.3e-15 * np.cos(finite)  # the AVX2 machine's largest difference, everywhere
    assert mismatches(rounding, reference) == []
    perturbed = {k: v.copy() for k, v in published_case.items()}
    perturbed["cube/resistance"].flat[finite[len(finite) // 2]] *= 1.0 + 1e-10
    assert mismatches(perturbed, reference) == [
        "cube/resistance: differs beyond rtol 1e-12 (largest relative difference 1e-10, or a changed inf/NaN pattern)"
    ]


if __name__ == "__main__" and sys.argv[1:] == ["--write"]:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        np.savez_compressed(FIXTURE, **_run_case(Path(tmp)))
    print(f"wrote {FIXTURE}")
