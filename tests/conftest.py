"""Shared fixtures: small scenarios that keep the suite fast."""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")
# One BLAS/OpenMP thread, as the CLI sets: small dense solves are far slower oversubscribed.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

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


@pytest.fixture(scope="session")
def small_discrete_atlas(tmp_path_factory) -> Path:
    """``atlas.nc`` of the small atlas on discrete asperities (:data:`DISCRETE_ATLAS`), computed once for
    the whole run (tests/test_atlas.py checks it, tests/test_predict_chain.py answers with its
    surrogate). Read it only: copy it to change it."""
    from g2tom.atlas import run as atlas
    from g2tom.atlas.design import AtlasDesign
    from tests.test_atlas import BASE

    design = AtlasDesign(mu=(2.0, 8.0), Pi=(10.0, 40.0), n_mu=2, n_pi=2, n_heldout=1)
    return _shared(tmp_path_factory, "small_discrete_atlas",
                   lambda folder: atlas.run_atlas(load_scenario("paper", {**BASE, **DISCRETE_ATLAS}), design, folder))
