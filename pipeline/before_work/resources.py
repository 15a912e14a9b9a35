"""Refusals before work on the plan's estimates, and what the CLI runs before any stage.

:func:`check_resources` refuses, with :class:`~g2tom.config.ConfigError` naming the parameter
that drives the excess (its value against the paper's), a run whose estimate
(:func:`g2tom.before_work.plan.estimate`) exceeds the machine's memory or :data:`MAX_SECONDS`.
:func:`prepare` is what the CLI runs before any stage: the checks, then the resolution of ``auto``
domains (:func:`g2tom.before_work.domains.resolve`), then the checks on the resolved cell count.
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any, Callable

from g2tom.before_work.plan import StageEstimate, available_memory, estimate
from g2tom.config import ConfigError, Scenario
from g2tom.before_work.scenario_checks import load_scenario

__all__ = ["MAX_SECONDS", "ANNOUNCE_AFTER", "check_resources", "prepare"]

#: Longest estimated run time accepted (s): beyond it a run is refused before work.
MAX_SECONDS = 7 * 24 * 3600.0
#: Commands that need no resolved domains nor resource checks.
_NO_DOMAINS = ("params", "predict", "roughness", "surface", "validate")
#: Stages whose estimate is printed when they are expected to take longer than this (s).
ANNOUNCE_AFTER = 10.0


#: Parameters whose values drive memory or time, in the order they are blamed.
_DRIVERS: tuple[str, ...] = (
    "roughness.eta", "contact.window", "oxide.lambda", "oxide.ks_ratio", "oxide.n_realizations",
    "oxide.max_realizations", "oxide.target_half_width", "oxide.min_realizations", "oxide.ensemble",
    "oxide.spectral_resolution", "oxide.period",
    "oxide.xi", "loading.n_delta", "loading.delta_min", "contact.n_radial", "contact.surfaces", "compute.oxide_chunk", "compute.cube_chunk",
    "fits.n_bootstrap", "indenter.radius", "indenter.shape", "roughness.sigma",
)


def _with(scenario: Scenario, key: str, value: Any) -> Scenario:
    """``scenario`` with ``key`` set to ``value``: a plain scenario (the key may be a domain)."""
    section, _, name = key.partition(".")
    attr = "lambda_" if name == "lambda" else name
    return Scenario.of(scenario, **{section: dataclasses.replace(getattr(scenario, section), **{attr: value})})


def _culprit(scenario: Scenario, measure: Callable[[Scenario], float]) -> tuple[str, Any, float]:
    """The parameter whose change from the paper's value grows ``measure`` the most."""
    reference = load_scenario("paper")
    current = measure(scenario)
    best: tuple[str, Any, float] = ("", None, 1.0)
    flat, ref_flat = scenario.flat(), reference.flat()
    for key in _DRIVERS:
        if flat[key] == ref_flat[key]:
            continue
        try:
            factor = current / measure(_with(scenario, key, ref_flat[key]))
        except (ConfigError, ValueError, ZeroDivisionError, OverflowError):
            continue
        if factor > best[2]:
            best = (key, flat[key], factor)
    return best


def _refuse(scenario: Scenario, what: str, needed: float, limit: float, unit: str,
            measure: Callable[[Scenario], float]) -> ConfigError:
    key, value, factor = _culprit(scenario, measure)
    value = f"{value:g}" if isinstance(value, float) else repr(value)
    fmt = (lambda v: f"{v / 2**30:.3g} GiB") if unit == "bytes" else (lambda v: f"{v / 3600:.3g} h")
    if key:
        return ConfigError(
            f"{key} = {value} is out of range for this machine: the {what} would need about "
            f"{fmt(needed)}, more than the {fmt(limit)} available ({factor:.3g} x the paper's value "
            f"{load_scenario('paper').flat()[key]!r}); bring it nearer that value (see `g2tom plan`)"
        )
    return ConfigError(f"the {what} would need about {fmt(needed)}, more than the {fmt(limit)} available "
                       f"(see `g2tom plan`)")


def _stage_measure(stage: str, field: str, workers: int | None) -> Callable[[Scenario], float]:
    def measure(s: Scenario) -> float:
        return next(getattr(e, field) for e in estimate(s, workers) if e.stage == stage)
    return measure


def check_resources(scenario: Scenario, workers: int | None = None, memory: float | None = None) -> list[StageEstimate]:
    """Refuse a run that cannot fit in memory (or would run longer than :data:`MAX_SECONDS`).

    An adaptive ensemble is judged at its typical counts; where a cell running to
    ``oxide.max_realizations`` would not fit, a warning says so (the run goes on: a typical run
    stops far below the cap).

    Parameters
    ----------
    scenario
        Resolved or not.
    workers
        Concurrent tasks (default: the core count).
    memory
        Bytes available (default: :func:`available_memory`).

    Returns
    -------
    list of StageEstimate
        The estimates, when the run fits.

    Raises
    ------
    ConfigError
        Naming the parameter that drives the excess, its value and the estimate.
    """
    from g2tom.before_work.domains import check_cell_count

    check_cell_count(scenario, memory or available_memory())
    limit = memory or available_memory()
    estimates = estimate(scenario, workers)
    for e in estimates:
        if not e.peak_bytes <= limit:
            raise _refuse(scenario, f"{e.stage} stage", e.peak_bytes, limit, "bytes",
                          _stage_measure(e.stage, "peak_bytes", workers))
    for e in estimates:
        if e.peak_bytes_cap is not None and not e.peak_bytes_cap <= limit:
            warnings.warn(f"the {e.stage} stage would need about {e.peak_bytes_cap / 2**30:.3g} GiB if a cell ran to "
                          f"oxide.max_realizations = {scenario.oxide.max_realizations}, more than the "
                          f"{limit / 2**30:.3g} GiB available (typical runs need {e.peak_bytes / 2**30:.3g} GiB); "
                          f"lower oxide.max_realizations if cells may run that far", ResourceWarning, stacklevel=2)
    total = sum(e.seconds for e in estimates)
    if not total <= MAX_SECONDS:
        worst = max(estimates, key=lambda e: e.seconds)
        raise _refuse(scenario, f"{worst.stage} stage's run time", worst.seconds, MAX_SECONDS, "seconds",
                      _stage_measure(worst.stage, "seconds", workers))
    return estimates


def prepare(command: str, scenario: Scenario, workers: int | None = None) -> tuple[Scenario, list[str]]:
    """What the CLI runs before any work: resource checks and the resolution of ``auto`` domains.

    Returns the resolved scenario (``scenario`` unchanged for commands that need neither: params,
    predict, roughness) and the plan's lines to announce once the other checks have passed (the
    stages' estimates that exceed :data:`ANNOUNCE_AFTER`).
    """
    if command in _NO_DOMAINS:
        return scenario, []
    from g2tom.before_work.domains import resolve

    check_resources(scenario, workers)
    resolved = resolve(scenario)
    notes = []
    for e in check_resources(resolved, workers):
        if e.seconds > ANNOUNCE_AFTER and command in (e.stage, "run"):
            span = (f" (adaptive ensemble: {e.seconds_range[0]:.3g} .. {e.seconds_range[1]:.3g} s)"
                    if e.seconds_range else "")
            notes.append(f"plan: {e.stage} estimated at ~{e.seconds:.3g} s{span} and ~{e.peak_bytes / 2**20:.0f} MiB "
                         f"peak (`g2tom plan` for all stages)")
    return resolved, notes
