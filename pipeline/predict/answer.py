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

import numpy as np
import xarray as xr

from g2tom.compute import single_threaded
from g2tom.config import ConfigError, Scenario, bundled_scenarios, read_input_text
from g2tom.config.arguments import holds_numbers, in_python_terms, is_number, is_path, refuse_argument
from g2tom.before_work import load_scenario
from g2tom.predict import atlas as atlas_file  # atlas_file.shipped_path, looked up at each call (tests patch it)
from g2tom.predict.atlas import NOT_IN_ATLAS, AtlasSurrogate, is_atlas_document, load_atlas_surrogate, predict_atlas
from g2tom.predict.domain import check_surface, with_measured_roughness
from g2tom.predict.predictor import predict
from g2tom.predict.queries import OutsideDomainError
from g2tom.scene import scene_plasticity
from g2tom.stages.surrogate_file import SurrogateTables, load_surrogate

__all__ = ["MODELS", "choose_surrogate", "own_surrogate_path", "predict_resistance", "predict_with",
           "surface_scenario"]

#: The models a prediction answers with: each cell's ln R'(ln F') curve, or Eq. 27.
MODELS = ("curve", "power_law")


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
        answers with its curve model only (its band is that model's) and reports Eq. 27 as
        ``resistance_power_law``: ``power_law`` is refused there.
    extrapolate
        Answer outside the surrogate's ranges (with an ExtrapolationWarning) instead of refusing.

    Returns
    -------
    xarray.Dataset
        The columns of :data:`g2tom.predict.queries.OUTPUT_COLUMNS` (from the atlas, less the
        single-scene band's components :data:`g2tom.predict.atlas.NOT_IN_ATLAS`), with
        ``attrs["answered_by"]`` naming the surrogate that answered.
    """
    _check_model(model)
    check_plasticity(surrogate, scenario)
    if isinstance(surrogate, SurrogateTables):
        return predict(surrogate, scenario, force, xi, lam, extrapolate=extrapolate, model=model)
    if model != "curve":
        raise ConfigError(f"model = {model!r} cannot be answered by the atlas surrogate {surrogate.source}: its band "
                          "is that of its curve model, so it answers with model = 'curve' (Eq. 27's value is its "
                          "column resistance_power_law); or give a run's own surrogate fitted on this surface "
                          "(--surrogate, surrogate=)")
    return predict_atlas(surrogate, scenario, force, xi, lam, extrapolate=extrapolate).drop_vars(NOT_IN_ATLAS)


def check_plasticity(surrogate: SurrogateTables | AtlasSurrogate, scenario: Scenario) -> None:
    """Refuse a surface whose caps are capped at a hardness the surrogate was not fitted with.

    The atlas covers elastic caps (its scenes have no hardness); a run's own surrogate answers the
    hardness it was fitted with (its attribute ``hardness``; none: elastic). A scene whose caps yield
    while held elastic is answered, with the warning :func:`g2tom.before_work.load_scenario` gives.

    Raises
    ------
    g2tom.predict.queries.OutsideDomainError
        Naming ``material.hardness``, its value and the surrogate's.
    """
    hardness = scenario.material.hardness
    fitted = surrogate.info.get("hardness") if isinstance(surrogate, SurrogateTables) else None
    if hardness == fitted:
        return
    if hardness is None:
        raise OutsideDomainError(f"material.hardness is unset (elastic caps), but the surrogate was fitted with "
                                 f"caps capped at {fitted:g} Pa: set material.hardness = {fitted:g}")
    if not isinstance(surrogate, SurrogateTables):
        kind = "the atlas surrogate covers elastic caps only"
    elif fitted is None:
        kind = "the surrogate was fitted on elastic caps"
    else:
        kind = f"the surrogate was fitted with material.hardness = {fitted:g} Pa"
    psi = scene_plasticity(scenario).index
    raise OutsideDomainError(f"material.hardness = {hardness:g} Pa (plasticity index psi = {psi:.3g}) is outside "
                             f"what the surrogate answers: {kind}")


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


def _check_model(model: Any) -> None:
    """Refuse a ``model`` not in :data:`MODELS`."""
    if model not in MODELS:
        raise refuse_argument("model", model, f"one of {', '.join(map(repr, MODELS))}")


def _check_arguments(**given: Any) -> None:
    """:func:`predict_resistance`'s arguments checked at its entry, each refusal naming the argument.

    Raises
    ------
    ConfigError
        Naming the first argument of the wrong kind, its value and what is allowed.
    """
    surface = given["surface"]
    if not (isinstance(surface, Scenario) or is_path(surface)):
        raise refuse_argument("surface", surface, "a Scenario, a bundled scenario's name "
                      f"({', '.join(bundled_scenarios())}), a TOML file or a height map file")
    for name, unit in (("force", "N, > 0"), ("xi", "in (0, 1)"), ("lam", "> 0")):
        if not holds_numbers(given[name]):
            raise refuse_argument(name, given[name], f"a number ({unit}), an array of numbers or an xarray.DataArray")
    if not is_path(given["data_dir"]):
        raise refuse_argument("data_dir", given["data_dir"], "a folder (a str or pathlib.Path)")
    if not (given["surrogate"] is None or is_path(given["surrogate"])):
        raise refuse_argument("surrogate", given["surrogate"], "None or a surrogate file (a str or pathlib.Path)")
    _check_model(given["model"])
    if not isinstance(given["extrapolate"], (bool, np.bool_)):
        raise refuse_argument("extrapolate", given["extrapolate"], "True or False")
    if not (given["overrides"] is None or isinstance(given["overrides"], Mapping)):
        raise refuse_argument("overrides", given["overrides"], 'None or a mapping {"section.key": value}')
    pixel = given["pixel_size"]
    if not (pixel is None or (is_number(pixel) and pixel > 0)):
        raise refuse_argument("pixel_size", pixel, "None or a number > 0 (m)")


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
        If an argument is of the wrong kind (naming it and its value) or
        out of range, or the query or surface lies outside the chosen surrogate's domain and
        ``extrapolate`` is False.
    """
    _check_arguments(surface=surface, force=force, xi=xi, lam=lam, data_dir=data_dir, surrogate=surrogate,
                     model=model, extrapolate=extrapolate, overrides=overrides, pixel_size=pixel_size)
    with in_python_terms():  # the checks `g2tom predict` shares name this function's arguments
        scenario = surface_scenario(surface, overrides, pixel_size)
        chosen = choose_surrogate(scenario, data_dir, surrogate)
        return predict_with(chosen, scenario, force, xi, lam, model=model, extrapolate=extrapolate)
