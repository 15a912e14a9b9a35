"""Shared fixtures: small scenarios that keep the suite fast."""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")
# One BLAS/OpenMP thread, as the CLI sets: small dense solves are far slower oversubscribed.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")


def _keep_freed_memory() -> None:
    """glibc's malloc hands the large arrays the stages allocate and free over and over back to the
    kernel and maps them afresh, a page fault for every page touched again (g2tom.physics.scratch
    says the same of dask.distributed's workers): measured on test_validate.py, 34 s -> 31 s with
    the freed memory kept instead, about a tenth of the suite spent in the kernel. This process only
    (each pytest worker): the commands the tests start as subprocesses keep the default allocator,
    so the memory they measure is a user's. Nothing where the C library is not glibc."""
    import ctypes
    import ctypes.util

    try:
        mallopt = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").mallopt
    except (OSError, AttributeError):
        return
    m_trim_threshold, m_mmap_threshold = -1, -3  # malloc.h
    mallopt(m_mmap_threshold, 32 << 20)  # the most glibc allows
    mallopt(m_trim_threshold, 1 << 30)


_keep_freed_memory()

import pytest  # noqa: E402

from g2tom.config import ResolvedScenario  # noqa: E402
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve  # noqa: E402

SMALL_OVERRIDES = {
    "loading.n_delta": 6,
    "contact.n_radial": 160,
    "oxide.xi": [0.2, 0.5, 0.8],
    "oxide.lambda": [1.0, 5.0, 13.0],
    "oxide.ensemble": "fixed",
    "oxide.n_realizations": 8,
    "oxide.chunk": 3,
    "cube.chunk": 3,
    "fits.n_bootstrap": 50,
}
#: The command-line arguments that give the ``small`` scenario.
SMALL_ARGS: tuple[str, ...] = ("--config", "paper_gt", *(a for k, v in SMALL_OVERRIDES.items() for a in ("--set", f"{k}={v}")))


@pytest.fixture(scope="session")
def paper() -> ResolvedScenario:
    """The default scenario (discrete asperities), unchanged."""
    return resolve(load_scenario("paper"))


@pytest.fixture(scope="session")
def paper_gt() -> ResolvedScenario:
    """The paper's study on Greenwood-Tripp's mean asperity layer (the grid spots' machinery), unchanged."""
    return resolve(load_scenario("paper_gt"))


@pytest.fixture(scope="session")
def small() -> ResolvedScenario:
    """``paper_gt`` shrunk to a few approaches, fractions, lengths and realizations: the grid
    machinery most tests exercise (the default's discrete scenes are in test_discrete_stages.py
    and test_pipeline_end_to_end.py)."""
    return resolve(load_scenario("paper_gt", SMALL_OVERRIDES))


def _shared(tmp_path_factory, name: str, build) -> Path:
    """``build(folder)``'s path, computed once for the whole run in ``<basetemp>/<name>``, whichever
    pytest-xdist worker asks first (the others wait on a lock and read it)."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):  # the workers' temporary folders share this parent
        root = root.parent
    with open(root / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        done = root / name / "path.txt"
        if not done.is_file():
            path = build(root / name)
            done.write_text(str(path))
        return Path(done.read_text())


@pytest.fixture(scope="session")
def small_atlas(tmp_path_factory) -> Path:
    """``atlas.nc`` of the small atlas (tests/test_atlas.py's ``BASE`` on ``paper_gt``, its ``DESIGN``:
    5 scenes and the invariance twin), computed once for the whole run. Read it only: copy it to change it."""
    from g2tom.atlas import run as atlas
    from tests.test_atlas import BASE, DESIGN

    return _shared(tmp_path_factory, "small_atlas",
                   lambda folder: atlas.run_atlas(load_scenario("paper_gt", BASE), DESIGN, folder))


#: The small atlas on discrete asperities (tests/test_atlas.py's ``BASE`` on the default's discrete
#: model with the disc rule, a fixed pool of 8 surfaces) and its design: mu 2 .. 8, Pi 10 .. 40.
DISCRETE_ATLAS = {"contact.model": "discrete", "oxide.spot_rule": "disc", "cube.model": "point",
                  "contact.surfaces": 8}
DISCRETE_ATLAS_DESIGN = {"atlas.mu_min": 2.0, "atlas.mu_max": 8.0, "atlas.pi_min": 10.0, "atlas.pi_max": 40.0,
                         "atlas.n_mu": 2, "atlas.n_pi": 2, "atlas.n_heldout": 1}


def discrete_atlas_args() -> list[str]:
    """``g2tom atlas``'s arguments for the small atlas on discrete asperities (``paper``, test_atlas's
    ``BASE``, :data:`DISCRETE_ATLAS` and :data:`DISCRETE_ATLAS_DESIGN`), one scene after another."""
    from tests.test_atlas import BASE

    sets = {**BASE, **DISCRETE_ATLAS, **DISCRETE_ATLAS_DESIGN}
    return ["atlas", "--config", "paper", "--workers", "1", "--no-progress",
            *(a for k, v in sets.items() for a in ("--set", f"{k}={v}"))]


@pytest.fixture(scope="session")
def small_discrete_atlas(tmp_path_factory) -> Path:
    """``atlas.nc`` of the small atlas on discrete asperities, run once for the whole run by the CLI
    (:func:`discrete_atlas_args`: its scenes, atlas.nc, surrogate.json and heldout.csv under
    ``<folder>/atlas``; its exit status and standard error in ``<folder>/atlas_cli.txt``, which
    tests/test_atlas.py's test of the CLI reads). tests/test_atlas.py checks it,
    tests/test_predict_chain.py answers with its surrogate. Read it only: copy it to change it."""
    import contextlib
    import io

    from g2tom.cli.main import main

    def build(folder: Path) -> Path:
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            status = main([*discrete_atlas_args(), "--data-dir", str(folder)])
        (folder / "atlas_cli.txt").write_text(f"{status}\n{err.getvalue()}")
        return folder / "atlas" / "atlas.nc"

    return _shared(tmp_path_factory, "small_discrete_atlas", build)


@pytest.fixture(scope="session")
def small_stages(tmp_path_factory) -> Path:
    """The ``small`` study run whole by ``g2tom run --no-bench`` (:data:`SMALL_ARGS`): every stage file
    (contact, oxide, cube, fits, surrogate), the figures and the report, computed once for the whole
    run; the warnings the run gave, one a line, in ``<folder>/../warnings.txt``.
    tests/test_pipeline_end_to_end.py checks it, tests/test_bad_inputs.py runs its catalog on it,
    tests/test_figures_style.py draws on it and tests/test_figures_point.py takes it as its Greenwood
    model's comparison run (``cube.model`` = greenwood being small's). Read it only: copy it to change it."""
    import warnings

    from g2tom.cli.main import main

    def build(folder: Path) -> Path:
        data = folder / "run"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            status = main(["run", "--data-dir", str(data), "--no-progress", "--no-bench", *SMALL_ARGS])
        assert status == 0
        (folder / "warnings.txt").write_text("".join(f"{w.category.__name__}: {w.message}\n" for w in caught))
        return data

    return _shared(tmp_path_factory, "small_stages", build)


@pytest.fixture(scope="session")
def cluster_address():
    """The scheduler address of a local ``dask.distributed`` cluster of two single-threaded worker
    processes, started once per pytest worker (3 s): the tests of a stage's bits on worker processes
    hand it to the stage as ``ComputeOptions(scheduler=...)`` (as `--scheduler` does) instead of
    each starting its own. The cluster g2tom starts itself (``--workers 2``) is still tested whole
    by tests/test_validate.py, tests/test_atlas.py, tests/test_compute.py and tests/test_signals.py."""
    import logging

    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.CRITICAL) as cluster:
        yield cluster.scheduler_address


#: Seconds each slow test file took with ``make test`` (its tests' setup, call and teardown summed, on
#: one of two workers of a quiet 2-core machine). Only the order matters: the scheduler below starts
#: the longest files first so that the two workers finish together; a file missing here runs after
#: them, in pytest-xdist's order (most tests first). Stale numbers cost balance, never correctness.
#: A file that asks first for a session fixture above carries its cost (test_figures_style.py:
#: small_stages, test_atlas.py: small_atlas and small_discrete_atlas, test_validate.py: cluster_address).
FILE_SECONDS = {
    "test_validate.py": 30, "test_signals.py": 30, "test_figures_style.py": 29, "test_atlas.py": 24,
    "test_surface.py": 18, "test_atlas_loads.py": 14, "test_atlas_design.py": 11, "test_plan.py": 10,
    "test_stability.py": 10, "test_frontier.py": 9, "test_pipeline_end_to_end.py": 8, "test_predict_chain.py": 8,
    "test_ensemble.py": 8, "test_reference_capped.py": 8, "test_bad_inputs.py": 8, "test_small_grids.py": 7,
    "test_barber_spots.py": 7, "test_discrete_contact.py": 7, "test_cube_stage.py": 6, "test_constriction.py": 6,
    "test_report.py": 6, "test_bench_output.py": 4, "test_reference_fft.py": 4, "test_compute.py": 4,
    "test_figures_contact.py": 4, "test_layers.py": 4, "test_domains.py": 4, "test_cap_law.py": 3,
    "test_frontier_prefix.py": 3, "test_step_ensemble.py": 3, "test_api_arguments.py": 3, "test_figures_point.py": 3,
    "test_surrogate.py": 3, "test_contact_stage.py": 3, "test_oxide_stage.py": 3, "test_bench_spots.py": 3,
}


def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile`` with the files handed out longest first (:data:`FILE_SECONDS`) instead of
    pytest-xdist's most tests first: the slow files were last alphabetically (signals, validate) and
    ran at the end on one worker while the other idled. A file still runs whole on one worker, in order."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class LongestFileFirst(LoadFileScheduling):
        _ordered = False

        def _assign_work_unit(self, node) -> None:
            if not self._ordered:  # the first assignment: the queue of files is complete, reorder it
                self._ordered = True
                files = list(self.workqueue)
                order = sorted(range(len(files)), key=lambda k: (-FILE_SECONDS.get(Path(files[k]).name, 0), k))
                units = list(self.workqueue.items())
                self.workqueue.clear()
                self.workqueue.update(units[k] for k in order)
            super()._assign_work_unit(node)

    return LongestFileFirst(config, log)
