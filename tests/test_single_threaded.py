"""Library entry points run with one BLAS thread (issue 32): ``g2tom.compute.single_threaded``."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from g2tom.compute import single_threaded

STAGE_MODULES = ("contact", "oxide", "cube", "fits", "surrogate")
#: The variables the console script sets to one thread before numpy loads.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _blas_threads() -> list[int]:
    np.ones(1) @ np.ones(1)  # numpy's BLAS loaded
    counts = [info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"]
    assert counts, "no BLAS library found by threadpoolctl"
    return counts


def test_one_blas_thread_inside_the_limits_restored_after() -> None:
    seen: list[list[int]] = []

    @single_threaded
    def probe(x: int, y: int = 0) -> int:
        """A probe."""
        seen.append(_blas_threads())
        return x + y

    with threadpool_limits(limits=2, user_api="blas"):
        assert _blas_threads() == [2] * len(_blas_threads())
        assert probe(1, y=2) == 3
        assert seen[-1] == [1] * len(seen[-1])
        single_threaded(lambda: probe(0))()  # nested calls
        assert seen[-1] == [1] * len(seen[-1])
        assert _blas_threads() == [2] * len(_blas_threads())  # restored
    assert probe.__doc__ == "A probe." and probe.__name__ == "probe"


@pytest.mark.parametrize("name", STAGE_MODULES)
def test_every_stage_build_and_run_and_the_predict_call_wear_it(name: str) -> None:
    wrapper_code = single_threaded(lambda: None).__code__
    module = importlib.import_module(f"g2tom.stages.{name}")
    for function in (module.build, module.run):
        assert function.__code__ is wrapper_code, f"{name}.{function.__name__} is not single_threaded"
    from g2tom.predict.answer import predict_resistance, predict_with

    assert predict_resistance.__code__ is wrapper_code and predict_with.__code__ is wrapper_code


def test_a_stage_build_runs_single_threaded(monkeypatch, small) -> None:
    """Inside a real stage call (fits.build), BLAS runs one thread."""
    from g2tom.stages import fits
    from tests.test_fits_stage import synthetic_cube

    seen: list[list[int]] = []
    original = fits.fitted_steps

    def spy(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        seen.append(_blas_threads())
        return original(*args, **kwargs)

    monkeypatch.setattr(fits, "fitted_steps", spy)
    cube = synthetic_cube(small, noise=0.2)
    with threadpool_limits(limits=2, user_api="blas"):
        fits.build(small, cube)
        assert _blas_threads() == [2] * len(_blas_threads())
    assert seen and all(c == [1] * len(c) for c in seen)


def test_the_entry_point_sets_one_thread_before_numpy_loads() -> None:
    """``g2tom.cli.main`` (the console script) sets the thread variables and loads no numpy on import."""
    probe = ("import os, sys; import g2tom.cli.main; "
             f"print('numpy' in sys.modules, *(os.environ.get(v) for v in {THREAD_VARIABLES!r}))")
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "1", "1", "1"]
