"""The driver of ``g2tom surface``: checks before work, every position, the dataset and its files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import dask
import numpy as np
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.compute import compute as run_tasks
from g2tom.config import ConfigError
from g2tom.config.arguments import holds_numbers, in_python_terms, is_number, is_path, is_whole, refuse_argument
from g2tom.physics.plasticity import plasticity_index
from g2tom.physics.spectrum_synthesis import IsotropicSpectrum, isotropic_spectrum, synthesize
from g2tom.physics.surface_spectrum import SummitParameters
from g2tom.progress import format_duration
from g2tom.reference import devices
from g2tom.reference.fft_surface import fft_surface
from g2tom.store import atomic_path
from g2tom.surface import windows
from g2tom.surface.dataset import surface_dataset
from g2tom.surface.maps import SurfaceMap, load_map, summits
from g2tom.surface.oxide import check_lengths, oxide_masks
from g2tom.surface.solve import PositionResult, solve_position
from g2tom.surface.statistical import attach_statistical
from g2tom.surface.study import DEFAULT_POSITIONS, Spot, SurfaceStudy, stream, study_of

__all__ = ["SECONDS_CONTACT", "SECONDS_CONDUCTANCE", "SECONDS_SOLVE_GPU", "COST_EXPONENT", "BYTES_PER_PADDED_PIXEL", "EXTEND_KEY",
           "FILES", "Prepared", "prepare", "window_of", "compute", "estimate", "plan_lines", "write_outputs",
           "surface_resistance"]

#: The spawn key of the windows drawn from the map's spectrum (the positions and oxide fields use others).
EXTEND_KEY = 2
#: Seconds of one contact solve on a 256^2 window (one core of the 2-core machine, ``make bench``'s
#: surface case).
SECONDS_CONTACT = 0.226
#: Seconds of one conductance (a punch) on a 256^2 window, measured as :data:`SECONDS_CONTACT`.
SECONDS_CONDUCTANCE = 0.042
#: Both grow as the window's side to this power (x5 and x5.6 at 512^2: larger windows hold larger contacts).
COST_EXPONENT = 2.5
#: Seconds of one solve (a contact or a punch) on a GPU: a floor of kernel launches and host round
#: trips, plus this much at a 1024^2 window, growing as :data:`COST_EXPONENT`. Measured on an H200 by
#: ``g2tom bench --only surface_gpu`` (the bench case, elastic: 2.1, 2.2 and 5.1 s a position of 10
#: forces x 10 solves at 256^2, 512^2 and 1024^2).
SECONDS_SOLVE_GPU = (0.020, 0.031)
#: Bytes a task holds per (2n)^2 pixel of its padded grid (about ten complex arrays in the solvers).
BYTES_PER_PADDED_PIXEL = 160
#: The files ``g2tom surface`` writes in its folder.
FILES = ("surface.nc", "surface.csv")


@dataclass(frozen=True)
class Prepared:
    """A study checked against its map: the map, the window's side (pixels) and the positions."""

    study: SurfaceStudy
    surface: SurfaceMap
    n: int
    positions: windows.Positions
    summits: SummitParameters | None
    spectrum: IsotropicSpectrum | None = None

    @property
    def synthesized(self) -> bool:
        """Whether the windows are drawn from the map's spectrum (the map is smaller than a window)."""
        return self.spectrum is not None

    @property
    def plasticity_index(self) -> float | None:
        """psi = (E*/H) sqrt(sigma/beta) of the map's summits, None without a hardness or summits."""
        if self.study.hardness is None or self.summits is None:
            return None
        return plasticity_index(self.study.e_star, self.study.hardness, self.summits.sigma, self.summits.beta)


def prepare(study: SurfaceStudy, paths: Sequence[str | Path], pixel_size: float | None = None) -> Prepared:
    """Read the map(s) and check everything before work: resolution, window, positions.

    Raises
    ------
    ConfigError
        On an unusable map, a pixel too coarse for the lightest force, a measured area too small for
        the heaviest, or a position off the measured area (one line each).
    """
    surface = load_map([Path(p) for p in paths], pixel_size, study.detrend)
    windows.check_resolution(study, surface)
    check_lengths(study, surface.pixel, max(surface.inside.shape) * surface.pixel)
    n = windows.window_pixels(study, surface)
    if study.extend == "spectrum" and not windows.valid_corners(surface.inside, n).any():
        try:
            spectrum = isotropic_spectrum(surface.heights, surface.inside, surface.pixel)
        except ValueError as exc:
            raise ConfigError(f"--extend = 'spectrum' cannot be used: {exc}") from None
        count = DEFAULT_POSITIONS if study.positions is None else study.positions
        synthesized = windows.Positions(np.full((count, 2), -1), np.ones(count, bool), count)
        return Prepared(study, surface, n, synthesized, summits(surface), spectrum)
    valid = windows.check_window(study, surface, n)
    if study.at is not None:
        corner = windows.spot_corner(surface, n, study.at.x, study.at.y, study.at.centre)
        positions = windows.Positions(corner[None, :], np.ones(1, bool), 1)
    else:
        positions = windows.choose_positions(valid, n, study.positions, study.seed)
    return Prepared(study, surface, n, positions, summits(surface))


def estimate(prepared: Prepared, workers: int, device: str = "cpu") -> tuple[float, float]:
    """The run's wall time (s) on ``workers`` CPU cores, or on the GPU one position at a time, and one
    task's memory (bytes): the constants :data:`SECONDS_CONTACT`, :data:`SECONDS_CONDUCTANCE` (CPU) or
    :data:`SECONDS_SOLVE_GPU` scaled to the window."""
    s, n = prepared.study, prepared.n
    cases = len(s.xi) * len(s.correlation_lengths) * s.fields
    positions = len(prepared.positions.corners)
    if device == "gpu":
        floor, at_1024 = SECONDS_SOLVE_GPU
        seconds = positions * len(s.forces) * (2 + cases) * (floor + at_1024 * (n / 1024) ** COST_EXPONENT)
    else:
        per_force = SECONDS_CONTACT + SECONDS_CONDUCTANCE * (1 + cases)
        rounds = -(-positions // max(1, workers))
        seconds = rounds * len(s.forces) * per_force * (n / 256) ** COST_EXPONENT
    memory = BYTES_PER_PADDED_PIXEL * (2 * n) ** 2 + (cases + 1) * n * n * 9
    return seconds, memory


def plan_lines(prepared: Prepared, workers: int = 1, device: str = "cpu") -> list[str]:
    """What the run will compute and about how long it takes on ``workers`` cores (or the GPU, for
    ``device`` ``gpu``), in a few lines (printed before work)."""
    s, m, n = prepared.study, prepared.surface, prepared.n
    count = len(prepared.positions.corners)
    independent = int(prepared.positions.independent.sum())
    cases = len(s.xi) * len(s.correlation_lengths) * s.fields
    shape = m.inside.shape
    lines = [
        f"surface: {' + '.join(m.files)}: {shape[0]} x {shape[1]} pixels of {m.pixel:.4g} m, "
        f"{m.measured_share:.1%} measured, rms height {m.rms_height:.4g} m ({m.detrend} removed"
        + (f"; {m.resampled}" if m.resampled else "") + ")",
        f"surface: window {n} x {n} pixels ({n * m.pixel:.4g} m); " + (
            f"the map holds none: {count} windows drawn from its isotropic power spectrum (--extend spectrum; "
            "wavelengths longer than the map at the plateau of its longest)" if prepared.synthesized else
            f"{count} position(s), {independent} independent (the measured area holds "
            f"{prepared.positions.capacity} independent windows)"),
        f"surface: {len(s.forces)} forces {s.forces[0]:.4g} .. {s.forces[-1]:.4g} N, "
        + ("elastic" if s.hardness is None else f"pressure capped at H = {s.hardness:.4g} Pa")
        + f", E* = {s.e_star:.4g} Pa, rho* = {s.rho:.4g} ohm m; clean"
        + (f" and {len(s.xi)} x {len(s.correlation_lengths)} oxide cases x {s.fields} fields" if cases else "")
        + f": {count * len(s.forces)} contact solves, {count * len(s.forces) * (1 + cases)} conductances",
    ]
    seconds, memory = estimate(prepared, workers, device)
    took = "under 1 s" if seconds < 0.5 else f"about {format_duration(seconds)}"
    if device == "gpu":
        lines.append(f"surface: {took} on the GPU, one position at a time, {memory / 2**20:.0f} MiB of its memory "
                     "(an H200's constants from make bench's surface_gpu case; other GPUs differ)")
    else:
        lines.append(f"surface: {took} on {workers} core(s), {memory / 2**20:.0f} MiB a task "
                     "(the constants of make bench's surface case; contacts larger than its can take longer)")
    if prepared.summits is not None:
        z = prepared.summits
        psi = prepared.plasticity_index
        lines.append(f"surface: the map's summits (4-pixel cutoff): sigma = {z.sigma:.4g} m, eta = {z.eta:.4g} m^-2, "
                     f"beta = {z.beta:.4g} m" + ("" if psi is None else f"; plasticity index psi = {psi:.3g}"))
    return lines


def window_of(prepared: Prepared, index: int) -> np.ndarray:
    """Position ``index``'s window of heights (m, (n, n)): the map's, or drawn from its spectrum with
    the position's own stream ``SeedSequence(seed, spawn_key=(EXTEND_KEY, index))``."""
    n, m = prepared.n, prepared.surface
    if prepared.synthesized:
        return synthesize(prepared.spectrum, n, m.pixel, stream(prepared.study.seed, EXTEND_KEY, index))
    row, col = prepared.positions.corners[index]
    return m.heights[row:row + n, col:col + n].copy()


def _solve(study: SurfaceStudy, window: np.ndarray, pixel: float, index: int, device: str) -> PositionResult:
    """One position's task: its operator (on ``device``), oxide fields and solve (each task owns its operator)."""
    n = window.shape[0]
    operator = fft_surface(n, pixel, study.e_star, devices.namespace(device))
    masks = oxide_masks(study, n, pixel, index) if study.oxidized else np.zeros((0, 0, 0, n, n), bool)
    return solve_position(study, operator, window, masks)


def compute(prepared: Prepared, options: ComputeOptions | None = None, device: str = "cpu") -> xr.Dataset:
    """Solve every position, one dask task each, where ``options`` says (default: one thread per
    core, the FFTs release the GIL; on the ``gpu``, one position at a time), and return the Dataset.

    ``device`` is ``cpu`` or ``gpu`` (resolved, :func:`g2tom.reference.devices.resolve`): where each
    position's operator, contact solves and punches run (the same arithmetic on CuPy).
    """
    s, m, n = prepared.study, prepared.surface, prepared.n
    if options is None:
        options = ComputeOptions(progress=False, workers=1 if device == "gpu" else None)
    tasks = [dask.delayed(_solve, pure=False)(s, window_of(prepared, index), m.pixel, index, device)
             for index in range(len(prepared.positions.corners))]
    results = list(run_tasks(*tasks, options=options, label="surface"))
    masks = oxide_masks(s, n, m.pixel, 0) if s.oxidized else np.zeros((0, 0, 0, n, n), bool)
    ds = surface_dataset(s, m, n, prepared.positions, results, window_of(prepared, 0), masks)
    ds.attrs["device"] = device
    if prepared.synthesized:
        sp = prepared.spectrum
        ds["position_x"][:] = np.nan
        ds["position_y"][:] = np.nan
        period, longest = 2 * n * m.pixel, 2 * np.pi / sp.q_min
        beyond = (f"longer ones up to the period {period:.4g} m synthesized at the plateau C(q_min) = "
                  f"{float(sp.power[0]):.4g} m^4" if period > longest else
                  f"none longer synthesized (the windows' period, {period:.4g} m, is shorter than the map)")
        ds.attrs["extended"] = (
            f"spectrum: every window drawn from the map's isotropic power spectrum (the map holds no window of "
            f"{n} pixels): wavelengths {2 * np.pi / sp.q_max:.4g} .. {longest:.4g} m measured, {beyond}")
    if prepared.summits is not None:
        z = prepared.summits
        ds.attrs.update(map_summit_sigma=z.sigma, map_summit_eta=z.eta, map_summit_beta=z.beta)
        if prepared.plasticity_index is not None:
            ds.attrs["plasticity_index"] = prepared.plasticity_index
    return ds


def _csv_rows(ds: xr.Dataset) -> list[str]:
    """One row per position, force and case (clean: xi, correlation length and field empty)."""
    rows = ["position,x_m,y_m,independent,force_N,xi,correlation_length_m,field,resistance_ohm"]
    for p in range(ds.sizes["position"]):
        head = (f"{p},{float(ds.position_x[p]):.9g},{float(ds.position_y[p]):.9g},"
                f"{int(ds.independent[p])}")
        for f, force in enumerate(ds.force.values):
            rows.append(f"{head},{force:.9g},,,,{float(ds.resistance_clean[p, f]):.9g}")
            if "resistance" not in ds:
                continue
            for a, xi in enumerate(ds.xi.values):
                for b, length in enumerate(ds.correlation_length.values):
                    for k in range(ds.sizes["field"]):
                        value = float(ds.resistance[a, b, p, k, f])
                        rows.append(f"{head},{force:.9g},{xi:.9g},{length:.9g},{k},{value:.9g}")
    return rows


def write_outputs(ds: xr.Dataset, folder: str | Path) -> list[Path]:
    """Write ``surface.nc`` and ``surface.csv`` (:data:`FILES`) atomically into ``folder``."""
    folder = Path(folder)
    nc, csv = (folder / name for name in FILES)
    with atomic_path(nc) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    with atomic_path(csv) as tmp:
        tmp.write_text("\n".join(_csv_rows(ds)) + "\n")
    return [nc, csv]


def _check_arguments(**given: Any) -> None:
    """:func:`surface_resistance`'s arguments checked at its entry, each refusal naming the argument.

    Raises
    ------
    ConfigError
        Naming the first argument of the wrong kind, its value and what is allowed.
    """
    maps = given["maps"]
    listed = [maps] if is_path(maps) else maps
    if not (isinstance(listed, (list, tuple)) and 1 <= len(listed) <= 2 and all(map(is_path, listed))):
        raise refuse_argument("maps", maps, "a height map file, or a list of two (a str or pathlib.Path each)")
    for name, unit in (("force", "N, > 0"), ("xi", "in (0, 1)"), ("correlation_length", "m, > 0")):
        value = given[name]
        if not (holds_numbers(value) or (name != "force" and np.size(value) == 0)):
            raise refuse_argument(name, value, f"a number ({unit}) or a list of numbers")
    for name, allowed in (("fields", "a whole number in [1, 1024]"), ("positions", "None or a whole number in [1, 4096]"),
                          ("window", "None or a whole number of pixels in [8, 8192]")):
        if not (is_whole(given[name]) or (name != "fields" and given[name] is None)):
            raise refuse_argument(name, given[name], allowed)
    at = given["at"]
    if not (at is None or at == "centre" or (isinstance(at, (list, tuple)) and len(at) == 2 and all(map(is_number, at)))):
        raise refuse_argument("at", at, "None, 'centre' or (x, y) in m from the centre of the map's first pixel")
    pixel = given["pixel_size"]
    if not (pixel is None or is_number(pixel)):
        raise refuse_argument("pixel_size", pixel, "None or a number (m)")
    if not (given["overrides"] is None or isinstance(given["overrides"], Mapping)):
        raise refuse_argument("overrides", given["overrides"], 'None or a mapping {"section.key": value}')
    for name in ("config", "data_dir"):
        if not is_path(given[name]):
            raise refuse_argument(name, given[name], "a name or file (a str or pathlib.Path)" if name == "config"
                                  else "a folder (a str or pathlib.Path)")
    if not (given["options"] is None or isinstance(given["options"], ComputeOptions)):
        raise refuse_argument("options", given["options"], "None or a g2tom.compute.ComputeOptions")


def surface_resistance(maps: str | Path | Sequence[str | Path], force: Any, *, xi: Any = (),
                       correlation_length: Any = (), config: str = "paper",
                       overrides: Mapping[str, Any] | None = None, pixel_size: float | None = None, fields: int = 8,
                       positions: int | None = None, at: tuple[float, float] | str | None = None, window: int | None = None,
                       detrend: str = "plane", extend: str = "none", options: ComputeOptions | None = None,
                       device: str = "cpu", data_dir: str | Path = "data") -> xr.Dataset:
    """The full-field resistance of a measured surface, as ``g2tom surface`` computes it.

    Parameters
    ----------
    maps
        One height map, or two whose composite (sum) is the rough body.
    force
        Normal forces F, N (> 0).
    xi, correlation_length
        Oxide fractions in (0, 1) and correlation lengths l_O, m (both or neither).
    config, overrides
        The scenario (a bundled name or a TOML file) and ``{"section.key": value}`` overrides: its
        ``material.*`` (E*, rho*, hardness), ``indenter.*`` and ``oxide.*`` (spectrum, seed) are used.
    pixel_size
        Pixel side, m (for maps that carry none).
    fields, positions
        Oxide fields per position; contact positions over the map (default: every independent window
        the map holds, at most 16).
    at
        ``(x, y)`` in m from the centre of the map's first pixel, or ``"centre"``: one position there.
    window
        Window side in pixels (default: the smallest that holds the heaviest force's contact).
    detrend
        ``plane`` (default) or ``none``.
    extend
        ``none`` (default: a map smaller than the window is refused) or ``spectrum`` (windows drawn
        from the map's own isotropic power spectrum, :mod:`g2tom.physics.spectrum_synthesis`).
    options
        Where the positions compute (``g2tom.compute.ComputeOptions``; default one thread per
        core, no progress line; one on the GPU).
    device
        ``cpu`` (default), ``gpu`` (CuPy: the optional extra ``gpu``) or ``auto`` (``gpu`` where
        CuPy sees one): where the full field's solves run.
    data_dir
        A run's data directory, whose own surrogate gives the statistical answer where it was
        fitted on the map's summits (:mod:`g2tom.surface.statistical`; else the atlas's).

    Returns
    -------
    xarray.Dataset
        surface.nc's contents.

    Raises
    ------
    ConfigError
        On any input out of range, before work.
    """
    from g2tom.before_work import load_scenario

    _check_arguments(maps=maps, force=force, xi=xi, correlation_length=correlation_length, fields=fields,
                     positions=positions, window=window, at=at, pixel_size=pixel_size, overrides=overrides,
                     config=config, data_dir=data_dir, options=options)
    with in_python_terms():  # the checks `g2tom surface` shares name this function's arguments
        try:
            device = devices.resolve(device)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        paths = [maps] if isinstance(maps, (str, Path)) else list(maps)
        scenario = load_scenario(config, dict(overrides or {}), rough_scene=False)
        spot = None
        if at is not None:
            spot = Spot(centre=True) if at == "centre" else Spot(x=float(at[0]), y=float(at[1]))
        study = study_of(scenario, force, xi=xi, correlation_lengths=correlation_length, fields=fields,
                         positions=positions, at=spot, window=window, detrend=detrend, extend=extend)
        prepared = prepare(study, paths, pixel_size)
    return attach_statistical(compute(prepared, options, device), scenario, prepared.summits, data_dir)
