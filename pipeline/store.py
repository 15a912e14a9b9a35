"""Stage files: atomic netCDF writes, provenance attributes and staleness checks.

Every stage writes exactly one netCDF4 file ``<data_dir>/<stage>.nc``. The file is first
written to a temporary name in the same directory and then renamed over the target, so an
interrupted or failed run never leaves a half-written dataset and never destroys the
previous one.
"""

from __future__ import annotations

import datetime
import functools
import json
import os
import shutil
import signal
import subprocess
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np
import xarray as xr

from g2tom import __version__
from g2tom.config import STAGE_UPSTREAM, Scenario
from g2tom.errors import StaleInputError, WriteError

__all__ = [
    "StaleInputError",
    "stage_path",
    "provenance",
    "write_dataset",
    "read_stage",
    "atomic_path",
    "check_writable",
    "signals_deferred",
    "write_errors",
    "stage_problem",
    "unreadable",
    "shaping_parameters",
    "git_commit",
]


#: The signals :func:`signals_deferred` holds.
_HELD = (signal.SIGINT, signal.SIGTERM)


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


def shaping_parameters(scenario: Scenario, stage: str) -> dict[str, Any]:
    """The parameters that shaped a stage's output: its own and those of every upstream stage."""
    params = dict(scenario.stage_parameters(stage))
    for upstream in STAGE_UPSTREAM[stage]:
        params.update(shaping_parameters(scenario, upstream))
    return dict(sorted(params.items()))


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """The git commit of the package's source tree (with ``-dirty`` if modified), or ''."""
    root = Path(__file__).resolve().parent.parent
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=5, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""
    return head + ("-dirty" if dirty else "")


def provenance(scenario: Scenario, stage: str) -> dict[str, Any]:
    """Attributes every output carries: scenario, the parameters that shaped it, version,
    git commit, creation time (CF ``history``) and config hashes."""
    params = shaping_parameters(scenario, stage)
    commit = git_commit()
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    attrs: dict[str, Any] = {
        "title": f"g2tom {stage} stage",
        "Conventions": "CF-1.10",
        "history": f"{now} written by g2tom {__version__}" + (f" (git {commit})" if commit else "")
                   + f", stage {stage}, scenario {scenario.name}",
        "g2tom_version": __version__,
        "g2tom_commit": commit or "unknown",
        "stage": stage,
        "scenario": scenario.name,
        "scenario_description": scenario.description,
        "config_hash": scenario.config_hash(stage),
        "parameters": json.dumps(params, sort_keys=True),
    }
    for upstream in STAGE_UPSTREAM[stage]:
        attrs[f"config_hash_{upstream}"] = scenario.config_hash(upstream)
    for key, value in params.items():
        attrs[key] = _attr_value(value)
    return attrs


@contextmanager
def signals_deferred() -> Iterator[None]:
    """SIGINT and SIGTERM held while the block runs, then raised again as they came.

    A Ctrl-C inside a netCDF write can stop it between taking xarray's HDF5 lock and the block
    that releases it: closing the file then waits on that lock for ever. Held here, the signal
    is raised again (to whatever handler was there before) once the block has finished and
    cleaned up. Outside the main thread (where no signal handler runs) nothing is done.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in _HELD}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(caught):
            signal.raise_signal(s)


def _size(n: int) -> str:
    """A byte count in words (``12 kB``, ``3.4 GB``)."""
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000:
            return f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} TB"


def _free(folder: Path) -> str:
    """`` (N free there)`` for the disk of ``folder`` (its nearest existing parent), or ''."""
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        return f" ({_size(shutil.disk_usage(folder).free)} free there)"
    except OSError:
        return ""


@contextmanager
def write_errors(target: str | Path, kept: str | None = None) -> Iterator[None]:
    """A failed write inside, as :class:`~g2tom.errors.WriteError` naming ``target``, why, and what was kept.

    Caught: every ``OSError`` (ENOSPC, EACCES, EROFS, EDQUOT ...) and the ``RuntimeError`` netCDF
    raises for a failed HDF5 write (``NetCDF: HDF error`` on a full disk).

    Parameters
    ----------
    target
        The file (or folder) being written.
    kept
        What the failure left as it was; default: the previous ``target`` if there is one.
    """
    target = Path(target)
    if kept is None:
        kept = f"the previous {target} is kept unchanged" if target.exists() else "nothing was written there"
    try:
        yield
    except (OSError, RuntimeError) as exc:
        if isinstance(exc, OSError):
            reason = exc.strerror or str(exc)
        elif str(exc).startswith("NetCDF"):
            reason = str(exc).splitlines()[0]
        else:
            raise
        raise WriteError(f"cannot write {target}: {reason}{_free(target.parent)}; {kept}") from exc


def check_writable(folder: str | Path, kept: str) -> None:
    """Make ``folder`` if needed and prove it writable with a throw-away file, before any work.

    Raises
    ------
    WriteError
        Naming the folder, the reason and ``kept`` (what stays as it was).
    """
    folder = Path(folder)
    with write_errors(folder, kept):
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder, prefix=".g2tom-write-check."):
            pass


@contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it over ``target`` on success only.

    Ctrl-C and SIGTERM wait until it is done (:func:`signals_deferred`); a failed write
    (:func:`write_errors`) raises :class:`~g2tom.errors.WriteError`, the previous ``target`` untouched.
    """
    target = Path(target)
    with signals_deferred(), write_errors(target):
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


def _fix(stage: str) -> str:
    return f"rebuild it with `g2tom {stage}` (or `make {stage}`)"


def stage_problem(data_dir: str | Path, stage: str, scenario: Scenario) -> str | None:
    """Why a stage's output cannot be used by ``scenario`` (one line), or None if it can.

    Missing, unreadable (truncated, not netCDF) and built from another configuration are
    told apart; each message names the file and the command that fixes it. Only the
    attributes are read, so this is cheap.
    """
    path = stage_path(data_dir, stage)
    if not path.is_file():
        return f"{path} is missing: run `g2tom {stage}` (or `make {stage}`) first"
    found, problem = _header(path, stage)
    if problem:
        return problem
    expected = scenario.config_hash(stage)
    if found != expected:
        return (f"{path} was built from a different configuration (config_hash {found}, "
                f"scenario '{scenario.name}' needs {expected}): re-run `g2tom {stage}` (or `make {stage}`)")
    return None


def _header(path: Path, stage: str) -> tuple[str | None, str | None]:
    """A stage file's ``config_hash`` attribute, or why the file cannot be opened."""
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return ds.attrs.get("config_hash"), None
    except (OSError, ValueError, RuntimeError) as exc:
        return None, f"{path} is unreadable ({_reason(exc)}): {_fix(stage)}"


def unreadable(path: str | Path, stage: str) -> str | None:
    """Why an existing stage file cannot be opened (naming the fixing command), or None."""
    return _header(Path(path), stage)[1]


def _reason(exc: BaseException) -> str:
    """The first line of an exception's message, without the file name netCDF4 appends."""
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return text.split(": '/")[0].split(": b'")[0]


def read_stage(data_dir: str | Path, stage: str, scenario: Scenario, *, allow_unconverged: bool = False,
               select: Callable[[xr.Dataset], xr.Dataset] | None = None) -> xr.Dataset:
    """Load a stage's output into memory, checking it matches ``scenario``.

    A contact file whose solver did not converge at some approach is refused unless
    ``allow_unconverged`` (later stages must not build on an unconverged contact). ``select``
    picks the part to load from the file opened lazily (``lambda ds: ds[["resistance"]]``):
    the rest is never read nor decompressed (most of a cube's seconds). Default: all of it.

    Raises
    ------
    StaleInputError
        If the file is missing, unreadable, its ``config_hash`` differs from the
        scenario's, or it holds an unconverged contact; the message names the file and the
        command that fixes it.
    """
    problem = stage_problem(data_dir, stage, scenario)
    if problem:
        raise StaleInputError(problem)
    path = stage_path(data_dir, stage)
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds = (ds if select is None else select(ds)).load()
    except (OSError, ValueError, RuntimeError) as exc:  # damaged past its header
        raise StaleInputError(f"{path} is unreadable ({_reason(exc)}): {_fix(stage)}") from None
    if stage == "contact" and "converged" in ds and not allow_unconverged and not ds["converged"].values.all():
        failed = ds["delta_sigma"].values[ds["converged"].values == 0] if "delta_sigma" in ds.coords else []
        c = scenario.contact
        raise StaleInputError(
            f"{path}: the {c.solver} solver did not converge at delta/sigma = "
            f"{', '.join(f'{v:.3g}' for v in failed)} (contact.max_iterations = {c.max_iterations}, "
            f"worst residual {float(ds['residual'].max()):.3g}): raise contact.max_iterations or "
            f"loosen the tolerance, then re-run `g2tom contact`")
    return ds
