"""One predict call for any surface: the surrogate ``g2tom predict`` would choose, and its answer.

:func:`choose_surrogate` picks the surrogate that answers a surface: the one given, else the run's
own (``<data_dir>/surrogate.json``, else ``surrogate.nc``) when it was fitted on this surface
(equal mu, Pi: :func:`g2tom.predict.domain.check_surface`), else the atlas surrogate
(``<data_dir>/atlas/surrogate.json``, else the one shipped in the package). :func:`predict_with` predicts
with either kind, and :func:`predict_resistance` does both from a scenario, a scenario's name or
TOML file, or a measured height map. ``g2tom predict`` calls the same functions.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import xarray as xr

from g2tom.compute import single_threaded
from g2tom.config import ConfigError, Scenario, bundled_scenarios, read_input_text
from g2tom.before_work import load_scenario
from g2tom.predict import atlas as atlas_file  # atlas_file.shipped_path, looked up at each call (tests patch it)
from g2tom.predict.atlas import NOT_IN_ATLAS, AtlasSurrogate, is_atlas_document, load_atlas_surrogate, predict_atlas
from g2tom.predict.domain import check_surface, with_measured_roughness
from g2tom.predict.predictor import predict
from g2tom.stages.surrogate_file import SurrogateTables, load_surrogate

__all__ = ["choose_surrogate", "own_surrogate_path", "predict_resistance", "predict_with", "surface_scenario"]


def own_surrogate_path(data_dir: str | Path) -> Path:
    """The run's own surrogate: ``<data_dir>/surrogate.json``, else ``<data_dir>/surrogate.nc``."""
    json_path = Path(data_dir) / "surrogate.json"
    return json_path if json_path.is_file() else Path(data_dir) / "surrogate.nc"


def choose_surrogate(scenario: Scenario, data_dir: str | Path = "data", surrogate: str | Path | None = None,
                     option: str = "surrogate") -> SurrogateTables | AtlasSurrogate:
    """The surrogate that answers ``scenario``'s surface, as ``g2tom predict`` chooses it.

    Parameters
    ----------
    scenario
        The surface (its groups mu, Pi decide between the run's own surrogate and the atlas's).
    data_dir
        A run's data directory (``make run``'s ``data``).
    surrogate
        A surrogate file that answers whatever the surface: a single-scene ``surrogate.json`` or
        ``surrogate.nc``, or an atlas ``surrogate.json`` (told apart by its format).
    option
        How the caller named ``surrogate``, for error messages (``--surrogate`` on the command line).

    Returns
    -------
    SurrogateTables or AtlasSurrogate
        ``surrogate`` if given; else the run's own when it exists and was fitted on this surface;
        else the atlas's (``<data_dir>/atlas/surrogate.json``, else the shipped one); else the
        run's own (which then refuses the surface, naming its groups).

    Raises
    ------
    ConfigError
        If the chosen file is missing or not a surrogate.
    """
    if surrogate is not None:
        path = Path(surrogate)
        if path.suffix == ".json" and path.is_file() and is_atlas_document(read_input_text(option, path)):
            return load_atlas_surrogate(path)
        return load_surrogate(path)
    own = own_surrogate_path(data_dir)
    data_atlas = Path(data_dir) / "atlas" / "surrogate.json"
    atlas = data_atlas if data_atlas.is_file() else atlas_file.shipped_path()
    if own.is_file():
        tables = load_surrogate(own)
        try:
            check_surface(tables, scenario, extrapolate=False)
            return tables
        except ConfigError:
            if atlas is None:
                return tables  # predict refuses the surface, naming the run's own surrogate
    return load_atlas_surrogate(atlas) if atlas is not None else load_surrogate(own)


@single_threaded
def predict_with(surrogate: SurrogateTables | AtlasSurrogate, scenario: Scenario, force: Any, xi: Any, lam: Any,
           model: str = "curve", extrapolate: bool = False) -> xr.Dataset:
    """R_el and its band from either kind of surrogate (:func:`choose_surrogate`).

    Parameters
    ----------
    surrogate
        A single-scene surrogate (:func:`g2tom.predict.predictor.predict`) or the atlas's
        (:func:`g2tom.predict.atlas.predict_atlas`).
    scenario
        The surface, material and indenter.
    force, xi, lam
        Normal force F (N, > 0), oxide fraction (in (0, 1)) and l_O sqrt(eta) (> 0): numbers, arrays
        that broadcast together, or xarray.DataArrays.
    model
        ``curve`` (default) or ``power_law`` (Eq. 27), for a single-scene surrogate; the atlas
        answers with its curve model and reports Eq. 27 as ``resistance_power_law``.
    extrapolate
        Answer outside the surrogate's ranges (with an ExtrapolationWarning) instead of refusing.

    Returns
    -------
    xarray.Dataset
        The columns of :data:`g2tom.predict.queries.OUTPUT_COLUMNS` (from the atlas, less the
        single-scene band's components :data:`g2tom.predict.atlas.NOT_IN_ATLAS`), with
        ``attrs["answered_by"]`` naming the surrogate that answered.
    """
    if isinstance(surrogate, SurrogateTables):
        return predict(surrogate, scenario, force, xi, lam, extrapolate=extrapolate, model=model)
    return predict_atlas(surrogate, scenario, force, xi, lam, extrapolate=extrapolate).drop_vars(NOT_IN_ATLAS)


def surface_scenario(surface: Scenario | str | Path, overrides: Mapping[str, Any] | None = None,
                     pixel_size: float | None = None) -> Scenario:
    """The scenario of a surface given as a Scenario, a scenario's name or TOML file, or a height map.

    Parameters
    ----------
    surface
        A :class:`~g2tom.config.Scenario` (used as it is); a bundled scenario's name or a
        ``.toml`` file (:func:`~g2tom.config.load_scenario`); or any other existing file, read as
        a measured height map whose summits' sigma, eta and beta replace the ``paper`` scenario's
        (as ``g2tom predict --roughness FILE``; heights in m).
    overrides
        ``{"section.key": value}`` applied to a loaded scenario (not to a Scenario given).
    pixel_size
        The height map's pixel size, m (.npy, netCDF and text maps).

    Raises
    ------
    ConfigError
        If the scenario or height map cannot be read, or a parameter is out of range.
    """
    if isinstance(surface, Scenario):
        if overrides:
            raise ConfigError("overrides apply to a scenario loaded by name or file: pass the Scenario with them applied")
        if pixel_size is not None:
            raise ConfigError("pixel_size is only used with a height map file as the surface")
        return surface
    path = Path(surface)
    if str(surface) in bundled_scenarios() or path.suffix.lower() == ".toml" or not path.is_file():
        if pixel_size is not None:
            raise ConfigError("pixel_size is only used with a height map file as the surface")
        return load_scenario(surface, overrides or {})
    return with_measured_roughness(load_scenario("paper", overrides or {}), path, pixel_size)


@single_threaded
def predict_resistance(surface: Scenario | str | Path, force: Any, xi: Any, lam: Any, *,
                       data_dir: str | Path = "data", surrogate: str | Path | None = None, model: str = "curve",
                       extrapolate: bool = False, overrides: Mapping[str, Any] | None = None,
                       pixel_size: float | None = None) -> xr.Dataset:
    """R_el of a surface with its band, answered as ``g2tom predict`` answers it.

    Parameters
    ----------
    surface
        A Scenario, a scenario's name or TOML file, or a measured height map file
        (:func:`surface_scenario`).
    force, xi, lam
        Normal force F (N, > 0), oxide fraction (in (0, 1)) and l_O sqrt(eta) (> 0): numbers, arrays
        that broadcast together, or xarray.DataArrays (broadcast by dimension name).
    data_dir
        The run's data directory: its own surrogate answers its own surface, the atlas's others
        (:func:`choose_surrogate`).
    surrogate
        A surrogate file that answers instead (either kind).
    model
        ``curve`` (default) or ``power_law`` (Eq. 27).
    extrapolate
        Answer outside the surrogate's ranges or surface (with a warning) instead of refusing.
    overrides
        ``{"section.key": value}`` for a scenario loaded by name or file.
    pixel_size
        A height map's pixel size, m.

    Returns
    -------
    xarray.Dataset
        R_el (Ohm) as ``resistance``, its band ``lower`` / ``upper`` and the columns of
        :data:`g2tom.predict.queries.OUTPUT_COLUMNS`; ``attrs["answered_by"]`` names the surrogate.

    Raises
    ------
    ConfigError
        If an input is out of range, or the query or surface lies outside the chosen surrogate's
        domain and ``extrapolate`` is False.
    """
    scenario = surface_scenario(surface, overrides, pixel_size)
    chosen = choose_surrogate(scenario, data_dir, surrogate)
    return predict_with(chosen, scenario, force, xi, lam, model=model, extrapolate=extrapolate)
