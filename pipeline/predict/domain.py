"""The domain of a surrogate: the surface it answers, and surfaces measured on topographies.

A single-scene surrogate (``make run``'s) was fitted on one surface: its ``surrogate.json`` and
``surrogate.nc`` record the scene's dimensionless groups (mu, Pi) (:mod:`g2tom.physics.groups`),
and :func:`check_surface` refuses a query surface whose groups differ by more than
:data:`GROUP_TOLERANCE`, unless the caller extrapolates (then a warning). E*, rho*, and the
dimensions at equal groups only scale F and R, so such surfaces are answered.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path
from g2tom.config import ConfigError, Scenario
from g2tom.predict.queries import ExtrapolationWarning
from g2tom.scene import scene_groups
from g2tom.stages.surrogate_file import SurrogateTables

__all__ = ["GROUP_INPUTS", "GROUP_TOLERANCE", "answered_by", "check_surface", "group_problems", "with_measured_roughness"]

#: The inputs that set each group, each raising it: (parameter, its unit), largest exponent first
#: (mu = (8/3) eta sigma sqrt(2 R* beta), Pi = eta R* sigma).
GROUP_INPUTS = {
    "mu": (("roughness.eta", "m^-2"), ("roughness.sigma", "m"), ("indenter.radius", "m"), ("roughness.beta", "m")),
    "Pi": (("roughness.eta", "m^-2"), ("indenter.radius", "m"), ("roughness.sigma", "m")),
}

#: Relative difference of mu or Pi within which a single-scene surrogate answers a surface.
GROUP_TOLERANCE = 1e-3


def answered_by(tables: "SurrogateTables") -> str:
    """Which surrogate answers: the run's own single-scene one, with its scene and groups."""
    info = tables.info
    scene = f"scenario {info['scenario']!r}, " if info.get("scenario") else ""
    groups = (f"mu = {info['mu']:.6g}, Pi = {info['Pi']:.6g}" if info.get("mu") is not None and info.get("Pi") is not None
              else "groups not recorded")
    return f"the run's own single-scene surrogate ({scene}{groups})"


def group_problems(scenario: Scenario, ranges: dict[str, tuple[float, float]], span: str) -> list[tuple[str, str]]:
    """The surface's groups outside ``ranges``, each with the inputs that bring it in.

    Parameters
    ----------
    scenario
        The surface: its roughness (sigma, eta, beta, m and m^-2) and sphere radius R* (m).
    ranges
        (low, high) of ``mu`` and ``Pi``.
    span
        What the ranges are, for the texts ("the domain").

    Returns
    -------
    list of (str, str)
        Per group outside: ``"<group> = <value> lies outside <span> [lo, hi]"`` and which way to
        move which inputs (:data:`GROUP_INPUTS`, with their values now) and by what factor at least.
    """
    values = dataclasses.asdict(scene_groups(scenario))
    problems = []
    for name, inputs in GROUP_INPUTS.items():
        lo, hi = ranges[name]
        value = values[name]
        if lo * (1 - 1e-12) <= value <= hi * (1 + 1e-12):
            continue
        verb, factor = ("raise", lo / value) if value < lo else ("lower", value / hi)
        named = [f"{key} ({_parameter(scenario, key):.3g} {unit} now)" for key, unit in inputs]
        problems.append((f"{name} = {value:.6g} lies outside {span} [{lo:.6g}, {hi:.6g}]",
                         f"{name} must {'rise' if verb == 'raise' else 'fall'} {factor:.3g}-fold at least: {verb} "
                         f"{', '.join(named[:-1])} or {named[-1]}"))
    return problems


def _parameter(scenario: Scenario, key: str) -> float:
    """The scenario's value of a ``section.name`` parameter."""
    section, name = key.split(".")
    return float(getattr(getattr(scenario, section), name))


def check_surface(tables: "SurrogateTables", scenario: Scenario, extrapolate: bool) -> None:
    """Refuse (or, extrapolating, warn about) a surface whose (mu, Pi) the surrogate was not fitted on.

    Raises
    ------
    ConfigError
        Unless ``extrapolate``: naming the group, its value and the covered range, and the
        surrogate; also when the surrogate records no groups or another indenter shape.

    Warns
    -----
    g2tom.predict.ExtrapolationWarning
        With ``extrapolate``, for the same cases.
    """
    query = scene_groups(scenario)
    info = tables.info
    problems = []
    if info.get("mu") is None or info.get("Pi") is None:
        problems.append("the surrogate records no (mu, Pi) of its scene (made by an older g2tom): re-run "
                        "`g2tom surrogate`")
    else:
        for name, value in (("mu", query.mu), ("Pi", query.Pi)):
            ref = float(info[name])
            if abs(value / ref - 1.0) > GROUP_TOLERANCE:
                lo, hi = ref * (1 - GROUP_TOLERANCE), ref * (1 + GROUP_TOLERANCE)
                problems.append(f"{name} = {value:.6g} of this surface lies outside the domain [{lo:.6g}, {hi:.6g}] "
                                f"of {answered_by(tables)}")
    shape = info.get("indenter_shape")
    if shape is not None and shape != scenario.indenter.shape:
        problems.append(f"indenter.shape = {scenario.indenter.shape!r} differs from the surrogate's {shape!r}")
    if not problems:
        return
    if not extrapolate:
        raise ConfigError(f"{problems[0]}: it would answer one surface with another surface's coefficients; "
                          "pass --extrapolate (extrapolate=True) to predict anyway")
    warnings.warn(f"{problems[0]}: the prediction uses another surface's coefficients", ExtrapolationWarning,
                  stacklevel=3)


def with_measured_roughness(scenario: Scenario, path: Path, pixel_size: float | None) -> Scenario:
    """``scenario`` with sigma (of the summits), eta and beta measured on a topography file.

    Raises
    ------
    ConfigError
        If the file cannot be read or measured (see :func:`g2tom.heightmap.measure`).
    """
    from g2tom.heightmap import measure

    measured = measure(path, pixel_size)
    roughness = dataclasses.replace(scenario.roughness, sigma=measured["sigma"], eta=measured["eta"],
                                    beta=measured["beta"])
    return dataclasses.replace(scenario, roughness=roughness)

