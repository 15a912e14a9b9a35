"""Stability map: the contact solve and the clean resistance far beyond the paper's scene.

Each case is the Greenwood-Tripp study (``paper_gt``) at a reduced resolution (:data:`FAST`) with one parameter
pushed to an extreme (sigma 1e-9..1e-3 m, eta 1e6..1e14 m^-2, beta 1e-7..1e-3 m, R*
1e-4..1 m, delta/sigma +10..-10, rho* over 12 decades, each indenter shape, and the oxide
fraction and correlation length at their edges). For each case :func:`evaluate` records
whether the scenario is accepted (or the one-line reason it is refused), whether every
approach converged, the iterations and worst residual, and the physical checks: no NaN or
negative value, force finite and growing with load, the clean-surface resistance finite and
falling with load, and for the sphere the ratio of the rough to the Hertz contact force at
the heaviest load relative to the smooth (Hertz) limit. ``make bench`` saves the map to
``<data_dir>/bench/stability.nc`` (:func:`write_map`); ``tests/test_stability.py`` asserts
on the same cases.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from g2tom.config import ConfigError, Scenario
from g2tom.before_work import load_scenario

__all__ = ["FAST", "CASES", "Case", "evaluate", "stability_map", "write_map", "run"]

#: Resolution of every case: coarse enough for a sweep, fine enough for the checks (one short
#: correlation length, so that small windows still hold Fourier modes).
FAST: dict[str, Any] = {"contact.n_radial": 160, "loading.n_delta": 8, "oxide.lambda": [1.0]}
#: Largest spot window (cells per side) for the clean-resistance check.
MAX_CELLS = 61


@dataclasses.dataclass(frozen=True)
class Case:
    """One point of the map: the parameter swept, its value and the overrides that set it."""

    parameter: str
    value: float | str
    overrides: dict[str, Any]

    @property
    def label(self) -> str:
        v = f"{self.value:.3g}" if isinstance(self.value, float) else str(self.value)
        return f"{self.parameter}={v}"


def _sweep(parameter: str, values: list[Any], extra: dict[str, Any] | None = None) -> list[Case]:
    return [Case(parameter, v, {parameter: v, **(extra or {})}) for v in values]


CASES: list[Case] = [
    *_sweep("roughness.sigma", [float(v) for v in np.logspace(-9, -3, 7)]),
    *_sweep("roughness.eta", [float(v) for v in np.logspace(6, 14, 5)]),
    *_sweep("roughness.beta", [float(v) for v in np.logspace(-7, -3, 5)]),
    *_sweep("indenter.radius", [float(v) for v in np.logspace(-4, 0, 5)]),
    *[Case("loading.delta", f"{hi:+g}..{lo:+g}", {"loading.delta_max": hi, "loading.delta_min": lo,
                                                  "loading.n_delta": 11})
      for hi, lo in ((10.0, 0.0), (0.0, -10.0), (10.0, -10.0))],
    *_sweep("material.rho", [float(v) for v in np.logspace(-12, 0, 5)]),
    *_sweep("indenter.shape", ["sphere", "cone", "flat_punch"],
            {"indenter.cone_angle": 0.1, "indenter.punch_radius": 5e-4, "indenter.edge_radius": 5e-3}),
    *[Case("hertz_limit", f"delta/sigma={d:g}", {"roughness.sigma": 1e-6, "loading.delta_max": 0.0,
                                                 "loading.delta_min": d}) for d in (-30.0, -100.0, -300.0)],
    *_sweep("oxide.xi", [[1e-6, 0.5, 1 - 1e-6]]),
    *_sweep("oxide.lambda", [[0.1], [200.0]]),
]


def _window(scenario: Scenario) -> Scenario:
    """The scenario with its spot window shrunk to at most ``MAX_CELLS`` cells per side (then a plain
    scenario: the contact stage resolves it again)."""
    cells = MAX_CELLS * scenario.cell_size / scenario.indenter.radius
    if scenario.contact.window <= cells:
        return scenario
    return Scenario.of(scenario, contact=dataclasses.replace(scenario.contact, window=cells))


def evaluate(case: Case) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Run one case: its map record and the raw arrays the checks were made on.

    Returns
    -------
    record
        ``status`` ('converged', 'unconverged', 'refused' or 'failed'), ``message``,
        ``iterations`` (largest over approaches), ``residual`` (worst), ``seconds`` and the
        booleans ``finite_nonnegative``, ``force_monotone``, ``resistance_falls``, the count
        ``open_circuits`` and, for the sphere at the heaviest load, ``hertz_ratio`` (central
        pressure over the Hertz one at the same force, -> 1 in the smooth limit) and
        ``roughness_parameter`` sigma R*/a^2.
    arrays
        ``force`` (N), ``resistance_clean`` (ohm, NaN when not computed), ``pressure``,
        ``area_fraction``, ``separation`` over (delta, r), ``converged`` over delta.
    """
    from g2tom.physics import constriction
    from g2tom.physics.spot_geometry import SpotGeometry
    from g2tom.stages import contact

    record: dict[str, Any] = {"status": "refused", "message": "", "iterations": 0, "residual": math.nan,
                              "seconds": 0.0, "finite_nonnegative": False, "force_monotone": False,
                              "resistance_falls": False, "hertz_ratio": math.nan, "roughness_parameter": math.nan,
                              "open_circuits": 0}
    from g2tom.before_work.domains import resolve

    try:
        scenario = resolve(load_scenario("paper_gt", {**FAST, **case.overrides}))
    except ConfigError as exc:
        record["message"] = str(exc)
        return record, {}
    start = time.perf_counter()
    try:
        with np.errstate(divide="ignore", invalid="ignore"):  # a lone spot's Holm radius is NaN by design
            ds = contact.build(_window(scenario))
    except (ConfigError, ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:
        record.update(status="failed", message=f"{type(exc).__name__}: {exc}")
        return record, {}
    radius = np.asarray(ds["spot_radius"].values, float)
    pitch = float(np.diff(ds["x"].values)[0])
    n = radius.shape[-1]
    clean = constriction.resistance(np.ones((1, n, n), bool), SpotGeometry.whole_window(radius, radius, pitch),
                                    scenario.material.rho, scenario.compute.interaction_sum).resistance[:, 0]
    record["seconds"] = round(time.perf_counter() - start, 4)
    arrays = {"force": ds["force"].values, "resistance_clean": np.asarray(clean, float),
              "converged": ds["converged"].values.astype(bool)}
    for name in ("pressure", "area_fraction", "separation"):
        arrays[name] = ds[name].values
    fields = [arrays[k] for k in ("force", "pressure", "area_fraction")]
    finite_r = arrays["resistance_clean"][np.isfinite(arrays["resistance_clean"])]
    record.update(
        status="converged" if arrays["converged"].all() else "unconverged",
        iterations=int(ds["iterations"].max()),
        residual=float(ds["residual"].max()),
        finite_nonnegative=bool(all(np.isfinite(f).all() and (f >= 0).all() for f in fields)
                                and not np.isnan(arrays["resistance_clean"]).any() and (finite_r > 0).all()),
        force_monotone=bool(np.all(np.diff(arrays["force"]) > 0)),
        resistance_falls=bool(np.all(np.diff(arrays["resistance_clean"][np.isfinite(arrays["resistance_clean"])]) < 0)),
        open_circuits=int(np.isinf(arrays["resistance_clean"]).sum()),
    )
    if not arrays["converged"].all():
        record["message"] = (f"{case.label}: the {scenario.contact.solver} solver stopped after "
                             f"{record['iterations']} iterations with residual {record['residual']:.3g}")
    if scenario.indenter.shape == "sphere":
        record["hertz_ratio"] = float(ds["pressure"].values[-1, 0] / ds["hertz_pressure"].values[-1, 0])
        record["roughness_parameter"] = float(ds["roughness_parameter"].values[-1])
    return record, arrays


def stability_map(cases: list[Case] | None = None) -> list[tuple[Case, dict[str, Any]]]:
    """Every case with its record (see :func:`evaluate`)."""
    return [(case, evaluate(case)[0]) for case in (CASES if cases is None else cases)]


def write_map(results: list[tuple[Case, dict[str, Any]]], target: str | Path) -> Path:
    """Save the map as a labelled netCDF file (dimension ``case``) atomically."""
    import xarray as xr

    from g2tom.bench.schema import STABILITY
    from g2tom.stages.schema import labelled
    from g2tom.store import atomic_path

    def var(key: str, dtype: Any = None) -> tuple:
        return labelled(STABILITY[key], np.array([r[key] for _, r in results], dtype=dtype))

    ds = xr.Dataset(
        {
            "status": var("status", str),
            "message": var("message", str),
            "converged": labelled(STABILITY["converged"],
                                  np.array([r["status"] == "converged" for _, r in results], np.int8)),
            "iterations": var("iterations", np.int32),
            "residual": var("residual", float),
            "seconds": var("seconds", float),
            "finite_nonnegative": var("finite_nonnegative", np.int8),
            "force_monotone": var("force_monotone", np.int8),
            "resistance_falls": var("resistance_falls", np.int8),
            "open_circuits": var("open_circuits", np.int32),
            "hertz_ratio": var("hertz_ratio", float),
            "roughness_parameter": var("roughness_parameter", float),
        },
        coords={
            "case": labelled(STABILITY["case"], np.arange(len(results))),
            "parameter": labelled(STABILITY["parameter"], np.array([c.parameter for c, _ in results], dtype=str)),
            "value": labelled(STABILITY["value"], np.array([c.label.partition("=")[2] for c, _ in results], dtype=str)),
        },
        attrs={"title": "g2tom stability map", "Conventions": "CF-1.10",
               "base": "paper_gt scenario with " + ", ".join(f"{k}={v}" for k, v in FAST.items())},
    )
    target = Path(target)
    with atomic_path(target) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    return target


def run(scenario: Scenario, data_dir: str | Path | None = None) -> dict[str, Any]:
    """Sweep :data:`CASES`, save ``<data_dir>/bench/stability.nc``; JSON-ready summary."""
    results = stability_map()
    if data_dir is not None:
        write_map(results, Path(data_dir) / "bench" / "stability.nc")
    status = [r["status"] for _, r in results]
    ran = [r for _, r in results if r["status"] in ("converged", "unconverged")]
    return {
        "cases": len(results),
        "converged": status.count("converged"),
        "unconverged": status.count("unconverged"),
        "refused": status.count("refused"),
        "failed": status.count("failed"),
        "worst_residual": max((r["residual"] for r in ran), default=math.nan),
        "max_iterations": max((r["iterations"] for r in ran), default=0),
        "all_finite_nonnegative": all(r["finite_nonnegative"] for r in ran),
        "all_force_monotone": all(r["force_monotone"] for r in ran),
        "all_resistance_falls": all(r["resistance_falls"] for r in ran),
        "open_circuits": sum(r["open_circuits"] for r in ran),
        "problems": [f"{c.label}: {r['status']} {r['message']}".strip() for c, r in results
                     if r["status"] != "converged" or not (r["finite_nonnegative"] and r["force_monotone"])],
    }
