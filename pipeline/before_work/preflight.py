"""Checks run before the first stage starts, so bad input fails in a second, not after work.

* the data directory exists (or can be made) and is writable;
* a ``--scheduler`` address is well formed and a dask scheduler answers there quickly (distributed's
  handshake, not only an accepted connection);
* the cross-stage constraints that need physics (config.py is a leaf and checks only what
  needs no computation): the fit's ``fits.min_force`` (or ``fits.min_force_normalized``, by
  ``fits.fit_range``) must be reached by at least two load
  steps of the contact stage, and at the heaviest approach at least two cells must touch
  (otherwise the Holm radius and every resistance are undefined). Both are judged on the
  contact stage's own output when ``contact.nc`` is current, otherwise on a coarse solve of
  the same scene (a few hundredths of a second).

Every failure is a :class:`~g2tom.config.ConfigError` naming the parameter, its value and
what is allowed; the CLI turns it into one line and exit status 2.
"""

from __future__ import annotations

import asyncio
import dataclasses
import errno
import os
import re
import socket
import tempfile
from pathlib import Path

import numpy as np

from g2tom.config import ConfigError, ResolvedScenario

__all__ = ["check_data_dir", "check_output_file", "check_scheduler", "check_scene",
           "scene_forces", "preflight"]

#: Seconds a scheduler has to accept a TCP connection.
CONNECT_TIMEOUT = 2.0
#: Radial nodes of the coarse solve used when contact.nc is not current.
COARSE_NODES = 96
#: Relative slack on coarse forces before a min_force is refused (the fits stage checks exactly).
FORCE_SLACK = 0.02
_SCHEMES = ("tcp", "tls", "inproc", "ucx", "ws", "wss")
_ADDRESS = re.compile(r"^(?:(?P<scheme>[a-z]+)://)?(?P<host>\[[0-9a-fA-F:]+\]|[A-Za-z0-9_.\-]+)?(?::(?P<port>[^:/]*))?/?$")


def check_data_dir(data_dir: str | Path) -> None:
    """Create ``data_dir`` if needed and prove it writable with a throw-away file.

    Raises
    ------
    ConfigError
        If the directory cannot be made or written, or is a file.
    """
    path = Path(data_dir)
    if path.exists() and not path.is_dir():
        raise ConfigError(f"--data-dir {str(path)!r} is not a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path, prefix=".g2tom-write-check."):
            pass
    except OSError as exc:
        reason = os.strerror(exc.errno) if exc.errno else str(exc)
        raise ConfigError(f"--data-dir {str(path)!r} is not writable ({reason}): choose another "
                          f"directory or fix its permissions") from None


def check_output_file(option: str, target: str | Path) -> None:
    """Refuse, before any work, an output file that could not be written at ``target``.

    Nothing is created: a missing folder on the way is made only when the file is written.

    Parameters
    ----------
    option
        How the user named the file (``--output``), for the message.
    target
        The file to be written (replaced if it exists).

    Raises
    ------
    ConfigError
        If ``target`` is a directory, lies under a file, or its nearest existing folder is not
        writable.
    """
    path = Path(target)
    where = f"{option} {str(path)!r}"
    if path.is_dir():
        raise ConfigError(f"{where} is a directory: give a file name, e.g. {str(path / 'predictions.csv')!r}")
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise ConfigError(f"{where} lies under {str(folder)!r}, which is a file, not a directory: give a path "
                          "in a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ConfigError(f"{where} cannot be written: {str(folder)!r} is not writable; choose another path "
                          "or fix its permissions")


def check_scheduler(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """Refuse a malformed scheduler address, or one where nothing answers within ``timeout`` s.

    Accepted: ``[scheme://]host:port`` with scheme one of tcp, tls, inproc, ucx, ws, wss and
    port 1..65535. tcp, tls, ws and wss addresses are probed with a plain TCP connection.
    """
    form = "[tcp://]HOST:PORT, e.g. tcp://127.0.0.1:8786"
    scheme = address.partition("://")[0] if "://" in address else "tcp"
    if scheme not in _SCHEMES:
        raise ConfigError(f"--scheduler {address!r}: scheme {scheme!r} is not one of {', '.join(_SCHEMES)}")
    if scheme == "inproc":  # an in-process scheduler (a test or a notebook): nothing to probe
        return
    m = _ADDRESS.match(address.strip())
    if not m or not m.group("host"):
        raise ConfigError(f"--scheduler {address!r} is not an address: must be {form}")
    port_text = m.group("port")
    if port_text is None or not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise ConfigError(f"--scheduler {address!r}: port {port_text!r} is out of range: must be an "
                          f"integer 1..65535 ({form})")
    if scheme == "ucx":
        return
    host = m.group("host").strip("[]")
    try:
        with socket.create_connection((host, int(port_text)), timeout=timeout):
            pass
        reason = _not_dask(address if "://" in address else f"tcp://{address}", timeout) if scheme == "tcp" else None
    except OSError as exc:
        if isinstance(exc, socket.timeout):
            reason = f"no answer within {timeout:g} s"
        else:
            reason = os.strerror(exc.errno) if exc.errno and exc.errno in errno.errorcode else str(exc)
    if reason:
        raise ConfigError(f"--scheduler {address!r}: no dask scheduler reachable at {host}:{port_text} "
                          f"({reason}); start one with `dask scheduler` or drop --scheduler")


def _not_dask(address: str, timeout: float) -> str | None:
    """Why what accepts connections at ``address`` is not a dask scheduler (no distributed handshake
    within ``timeout`` s: an HTTP server, say, on which a client would wait for ever), or None."""
    try:
        from distributed.comm import connect
    except ImportError:  # the client names the missing extra
        return None

    async def handshake() -> None:
        comm = await connect(address, timeout=timeout)
        await comm.close()

    try:
        asyncio.run(asyncio.wait_for(handshake(), timeout))
    except (asyncio.TimeoutError, TimeoutError):
        return f"something accepts connections there but gave no dask handshake within {timeout:g} s"
    except Exception as exc:  # whatever the other end sent instead: garbage, an HTTP reply, a closed stream
        return f"something accepts connections there but does not speak dask's protocol ({type(exc).__name__})"
    return None


def scene_forces(scenario: ResolvedScenario, data_dir: str | Path | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Force (N) of every approach, how many cells touch at each, and how many asperities
    Greenwood-Tripp expects to touch at each (``2 pi eta int P(z > h(r)) r dr``).

    From the contact stage's output when it is current; otherwise from a coarse solve of
    the same scene (``COARSE_NODES`` radial nodes, about 0.05 s), where a cell touches when
    its centre lies inside the outermost node with a nonzero area fraction.
    """
    from scipy.special import erfc

    from g2tom.physics.radial_grid import force_weights
    from g2tom.store import stage_path, stage_problem  # xarray only when needed

    rough = scenario.roughness

    def asperities(r: np.ndarray, h: np.ndarray) -> np.ndarray:
        return 0.5 * erfc(h / (rough.sigma * np.sqrt(2.0))) @ (rough.eta * force_weights(r))

    if data_dir is not None and stage_problem(data_dir, "contact", scenario) is None:
        import xarray as xr

        with xr.open_dataset(stage_path(data_dir, "contact"), engine="netcdf4") as ds:
            force = ds["force"].values
            touching = np.count_nonzero(ds["spot_radius"].values > 0, axis=(-2, -1))
            expected = asperities(ds["r"].values, ds["separation"].transpose("delta", "r").values)
        return force, touching, expected
    from g2tom.before_work.domains import solve_scenario
    from g2tom.contact_solution import fields
    from g2tom.physics.grid import cell_centres
    from g2tom.physics.spots import cell_radii

    coarse = dataclasses.replace(
        scenario, contact=dataclasses.replace(
            scenario.contact, n_radial=min(scenario.contact.n_radial, COARSE_NODES)))
    r, sols = solve_scenario(coarse)
    f = fields(coarse, r, sols)
    x = cell_centres(scenario.n_cells, scenario.cell_size)
    r_cells = np.sort(cell_radii(x, x).ravel())
    edge = np.array([r[np.nonzero(a > 0)[0][-1]] if (a > 0).any() else -1.0 for a in f["area"]])
    return f["force"], np.searchsorted(r_cells, edge, side="right"), asperities(r, f["h"])


def check_scene(scenario: ResolvedScenario, data_dir: str | Path | None = None) -> None:
    """The cross-stage constraints that need the contact solution (see the module docstring).

    Raises
    ------
    ConfigError
        Naming the parameter at fault, its value and the range the scene allows.
    """
    force, touching, expected = scene_forces(scenario, data_dir)
    heaviest = int(np.argmin(scenario.deltas))
    from g2tom.models import contact_model  # here: the command line imports this module before numpy

    contact_model(scenario).check_reach(scenario, float(expected[heaviest]))
    rough, loading = scenario.roughness, scenario.loading
    if not np.isfinite(force).all():
        raise ConfigError(
            f"roughness.sigma = {rough.sigma!r}, loading.delta_min = {loading.delta_min!r}: the contact "
            f"solve gives non-finite forces; this scene is outside what the solver handles")
    if touching[heaviest] < 2:
        raise ConfigError(
            f"roughness.sigma = {rough.sigma!r} is out of range for this scene: at the heaviest approach "
            f"(loading.delta_min = {loading.delta_min!r} sigma) only {int(touching[heaviest])} cell(s) of "
            f"pitch 1/sqrt(eta) = {scenario.cell_size:.3g} m touch, so the Holm radius and the resistance are "
            f"undefined; increase roughness.sigma or lower loading.delta_min")
    if scenario.fits.fit_range == "force":
        key, threshold, values, unit = "min_force", scenario.fits.min_force, force, " N"
    else:
        key, threshold, values, unit = ("min_force_normalized", scenario.fits.min_force_normalized,
                                        force / scenario.force_scale, "")
    reached = int(np.sum(values * (1.0 + FORCE_SLACK) >= threshold))
    if reached < 2:
        top = float(np.sort(values)[-2]) if values.size >= 2 else float(values.max())
        raise ConfigError(
            f"fits.{key} = {threshold:g} is out of range: only {reached} load step(s) "
            f"reach it (contact forces {values.min():.3g}..{values.max():.3g}{unit}); a fit needs >= 2, so it "
            f"must be <= {top:.3g}{unit} for this scene")


def preflight(scenario: ResolvedScenario, data_dir: str | Path, scheduler: str | None = None,
              scene: bool = True) -> None:
    """Everything a computing command checks before it starts: directory, scheduler, scene."""
    check_data_dir(data_dir)
    if scheduler:
        check_scheduler(scheduler)
    if scene:
        check_scene(scenario, data_dir)
