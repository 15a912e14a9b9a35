"""The checks across a scenario's parameters: settings that rule each other out, run as it is loaded.

:func:`load_scenario` reads a scenario (:func:`g2tom.config.read_scenario`: each value against
its own declared range) and runs :func:`check_scenario` on it: a combination that cannot work stops
the run before any work, with one :class:`~g2tom.config.ConfigError` naming the parameter, its value
and what is allowed (exit status 2 from the CLI). This module imports no numpy at the top: the contact
models (:mod:`g2tom.models`) are imported where their checks run.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path
from typing import Any, Iterable, Mapping

from g2tom.before_work.window_checks import check_domains
from g2tom.config import AUTO, SECTIONS, ConfigError, Scenario, parameter_key, read_scenario

__all__ = ["check_scenario", "load_scenario", "with_control_variate"]


#: Largest integer a netCDF attribute (64-bit signed) can record.
_INT_MAX = 2**63 - 1


def _check_point_model(s: Scenario) -> None:
    """The point model and resistive films need radius weights; the point model, an operator it can
    apply; the lattice term belongs to the point model."""
    if s.cube.lattice_constant > 0 and s.cube.model != "point":
        raise ConfigError(
            f"cube.lattice_constant = {s.cube.lattice_constant!r} is not allowed with cube.model = "
            f"{s.cube.model!r}: the lattice self term belongs to cube.model = 'point' (must be 0 otherwise)"
        )
    if s.cube.model == "point" and s.compute.interaction_sum not in ("auto", "folded", "gemm", "direct"):
        raise ConfigError(
            f"compute.interaction_sum = {s.compute.interaction_sum!r} is not allowed with cube.model = 'point': must be one of "
            "'auto', 'folded', 'gemm', 'direct'"
        )
    needs_radius = "cube.model = 'point'" if s.cube.model == "point" else (
        "oxide.film = 'resistive'" if s.oxide.film == "resistive" else None)
    if needs_radius and s.cube.weights != "radius":
        raise ConfigError(
            f"cube.weights = {s.cube.weights!r} is not allowed with {needs_radius}: must be 'radius' "
            "(only radius weights make Greenwood's form the Rayleigh quotient of the point model)"
        )


def _check_spots(s: Scenario) -> None:
    """``expected`` and ``asperities`` spots need the separation at the cells and radius weights."""
    if s.contact.spots == "mean_area":
        return
    if s.contact.area_interpolation != "separation":
        raise ConfigError(
            f"contact.area_interpolation = {s.contact.area_interpolation!r} is not allowed with "
            f"contact.spots = {s.contact.spots!r}: must be 'separation' (these spots are computed from "
            "the separation at each cell centre)"
        )
    if s.cube.weights != "radius":
        raise ConfigError(
            f"cube.weights = {s.cube.weights!r} is not allowed with contact.spots = {s.contact.spots!r}: "
            "must be 'radius' (cell-area weights are the published code's convention for mean_area spots)"
        )


def _control_variate_conflict(s: Scenario) -> str | None:
    """Why the control variate cannot adjust ``s``'s geometric mean (its expectation is exact for
    discrete spots, the theoretical threshold and ideal amplitudes only, and it adjusts the
    geometric mean of an insulating film's ensemble), as the end of a refusal; None where it can."""
    from g2tom.models import contact_model, models_that  # here: the command line imports this module before numpy

    if not contact_model(s).has_clean_share:
        return (f"contact.model = {s.contact.model!r} is not allowed with fits.control_variate = 'clean_share': "
                f"must be {models_that(lambda m: m.has_clean_share)} (the control is the discrete spots' clean share)")
    for name, value, allowed, why in (
        ("oxide.threshold", s.oxide.threshold, "theoretical", "its expectation needs one threshold for every field"),
        ("oxide.amplitudes", s.oxide.amplitudes, "ideal",
         "its expectation is exact for the random-phase field of fixed amplitudes"),
        ("fits.reduction", s.fits.reduction, "geometric_mean", "the control variate adjusts the mean of ln R"),
        ("oxide.film", s.oxide.film, "insulating", "a resistive film conducts where the control counts no share"),
    ):
        if value != allowed:
            return (f"{name} = {value!r} is not allowed with fits.control_variate = 'clean_share': "
                    f"must be {allowed!r} ({why})")
    return None


def _check_control_variate(s: Scenario) -> None:
    """``fits.control_variate = "clean_share"`` only where ``_control_variate_conflict`` finds none."""
    if s.fits.control_variate == "clean_share" and (conflict := _control_variate_conflict(s)):
        raise ConfigError(conflict)


def with_control_variate(s: Scenario) -> Scenario:
    """``s`` with ``fits.control_variate = "auto"`` settled: ``"clean_share"`` where the control
    variate applies (discrete spots, the theoretical threshold, ideal amplitudes, the geometric mean, an
    insulating film), else ``"none"``; any other value kept."""
    if s.fits.control_variate != "auto":
        return s
    chosen = "none" if _control_variate_conflict(s) else "clean_share"
    return dataclasses.replace(s, fits=dataclasses.replace(s.fits, control_variate=chosen))


def _check_hardness(s: Scenario) -> None:
    """A hardness needs a contact model whose caps can yield (:attr:`g2tom.models.ContactModel.caps_yield`)."""
    if s.material.hardness is None:
        return
    from g2tom.models import contact_model, models_that  # here: the command line imports this module before numpy

    model = contact_model(s)
    if not model.caps_yield:
        raise ConfigError(f"material.hardness = {s.material.hardness:g} Pa needs contact.model = "
                          f"{models_that(lambda m: m.caps_yield)}: {model.name}'s caps are elastic only")


def _check_step_target(s: Scenario) -> None:
    """A per-step target grows an adaptive ensemble on discrete spots, for the geometric mean."""
    from g2tom.models import step_target_conflicts  # here: the command line imports this module before numpy

    conflicts = step_target_conflicts(s)
    if s.oxide.step_half_width == 0 or not conflicts:
        return
    name, value, allowed, why = conflicts[0]
    raise ConfigError(f"{name} = {value!r} is not allowed with oxide.step_half_width = "
                      f"{s.oxide.step_half_width!r}: must be {allowed!r} ({why})")


def check_scenario(s: Scenario, rough_scene: bool = True) -> None:
    """Every check across parameters of a scenario, run as it is loaded (before any work).

    The settings that rule each other out (:func:`_check_point_model`, :func:`_check_spots`,
    :func:`g2tom.models.check_contact_model`, :func:`_check_control_variate`, :func:`_check_step_target`), integers a netCDF attribute cannot hold, the approaches' order,
    the atlas's box and, once ``contact.window`` and ``contact.r_max`` are both numbers, the
    window against the radial domain and the oxide band
    (:func:`g2tom.before_work.window_checks.check_domains`); where ``rough_scene``, the warning of
    caps that yield but are held elastic.

    Raises
    ------
    ConfigError
        Naming the parameter, its value and what is allowed.
    """
    _check_point_model(s)
    _check_spots(s)
    from g2tom.models import check_contact_model  # here: the command line imports this module before numpy

    check_contact_model(s)
    _check_hardness(s)
    _check_control_variate(s)
    _check_step_target(s)
    for section in SECTIONS:
        obj = getattr(s, section)
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if isinstance(value, int) and not isinstance(value, bool) and abs(value) > _INT_MAX:
                raise ConfigError(
                    f"{section}.{parameter_key(f)} = {value!r} is out of range: must be <= 2**63 - 1 = {_INT_MAX} "
                    f"(stored as a 64-bit integer in every output file)")
    if s.loading.delta_min > s.loading.delta_max:
        raise ConfigError(
            f"loading.delta_min = {s.loading.delta_min!r} is out of range: must be <= "
            f"loading.delta_max = {s.loading.delta_max!r} (sigma)"
        )
    if s.loading.n_delta > 1 and s.loading.delta_min == s.loading.delta_max:
        raise ConfigError(
            f"loading.delta_min = {s.loading.delta_min!r} must differ from loading.delta_max = "
            f"{s.loading.delta_max!r} when loading.n_delta = {s.loading.n_delta} > 1 (sigma)"
        )
    for low, high in (("mu_min", "mu_max"), ("pi_min", "pi_max")):
        if not getattr(s.atlas, low) < getattr(s.atlas, high):
            raise ConfigError(f"atlas.{high} = {getattr(s.atlas, high)!r} is out of range: must be > "
                              f"atlas.{low} = {getattr(s.atlas, low)!r}")
    if AUTO not in (s.contact.window, s.contact.r_max):
        check_domains(s)
    if rough_scene:
        _warn_plasticity(s)


def _warn_plasticity(s: Scenario) -> None:
    """One warning where the scene's caps yield (its plasticity index, :class:`g2tom.scene.Plasticity`)
    but are held elastic (``material.hardness`` unset)."""
    from g2tom.scene import scene_plasticity  # here: the command line imports this module before numpy

    warning = scene_plasticity(s).warning()
    if warning is not None:
        warnings.warn(warning, stacklevel=3)


def load_scenario(config: str | Path = "paper", overrides: Iterable[str] | Mapping[str, Any] = (), *,
                  rough_scene: bool = True) -> Scenario:
    """Load a bundled scenario by name or a TOML file, apply overrides, settle
    ``fits.control_variate = "auto"`` (:func:`g2tom.before_work.scenario_checks.with_control_variate`),
    and check every value and every combination (:func:`check_scenario`).

    Parameters
    ----------
    config
        A bundled scenario name (:func:`g2tom.config.bundled_scenarios`) or a path to a TOML file,
        which may set ``base = "paper"`` to start from a bundled scenario.
    overrides
        ``"section.key=value"`` strings (values in TOML syntax) or a mapping ``{"section.key": value}``.
    rough_scene
        Whether the scenario's ``roughness.*`` describe the surface computed (False for a measured
        map, ``g2tom surface``: no warning about the plasticity index of the scenario's roughness).

    Raises
    ------
    ConfigError
        Naming the parameter, its value and the allowed range.
    """
    scenario = with_control_variate(read_scenario(config, overrides))
    check_scenario(scenario, rough_scene)
    return scenario
