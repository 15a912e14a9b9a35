"""The frontier's prefix curve: an adaptive cube's fast-rule half-widths at prefixes of every cell.

From an existing adaptive ``<data_dir>/cube.nc`` (else skipped with a note): per (xi, lambda), the
fast rule's half-widths of alpha and gamma (:func:`g2tom.stages.cube_rounds.half_widths`) at
log-spaced prefixes n = 50 .. the cell's count, and the cube time prorated to n.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.bench.schema import FRONTIER
from g2tom.config import Scenario
from g2tom.stages.schema import labelled

__all__ = ["PREFIX_FROM", "PREFIX_POINTS", "prefix_counts", "prefix_curve", "adaptive_prefix", "prefix_summary"]

#: Prefix curve of an adaptive cube: the smallest prefix and the points per (xi, lambda).
PREFIX_FROM = 50
PREFIX_POINTS = 12


def prefix_counts(count: int) -> np.ndarray:
    """:data:`PREFIX_POINTS` prefixes log-spaced from ``min(PREFIX_FROM, count)`` to ``count`` (rounded)."""
    return np.round(np.geomspace(min(PREFIX_FROM, count), count, PREFIX_POINTS)).astype(np.int64)


def prefix_curve(scenario: Scenario, cube_ds: xr.Dataset, cube_seconds: float) -> xr.Dataset:
    """The fast rule's half-widths and the prorated time at prefixes of every (xi, lambda) of a cube.

    Parameters
    ----------
    scenario
        The scenario the cube was built with (``fits.min_force`` and ``fits.confidence`` set the rule).
    cube_ds
        An adaptive cube: ``resistance`` (xi, lambda, delta, realization), NaN beyond
        ``n_realizations`` (xi, lambda); ``force`` and ``force_normalized`` (delta).
    cube_seconds
        Wall time of the cube stage that built ``cube_ds`` (s), spread evenly over every
        realization of every cell.

    Returns
    -------
    xarray.Dataset
        ``prefix_n``, ``prefix_alpha_halfwidth`` (relative), ``prefix_gamma_halfwidth``
        (absolute) and ``prefix_seconds``, each (cube_xi, cube_lambda, prefix_step); the last
        step is the cell's count, where the half-widths equal the cube's ``rule_*_half_width``.
    """
    from g2tom.stages import cube_rounds

    rule = cube_rounds.stopping_rule(scenario, cube_ds["force"].values, cube_ds["force_normalized"].values)
    resistance = cube_ds["resistance"].transpose("xi", "lambda", "delta", "realization").values
    counts = cube_ds["n_realizations"].transpose("xi", "lambda").values.astype(np.int64)
    per_realization = cube_seconds / counts.sum()
    shape = (*counts.shape, PREFIX_POINTS)
    n = np.zeros(shape, np.int64)
    alpha, gamma = np.full(shape, np.nan), np.full(shape, np.nan)
    for i, j in np.ndindex(counts.shape):
        n[i, j] = prefix_counts(int(counts[i, j]))
        a, g = cube_rounds.half_widths(resistance[i, j][None, :, : counts[i, j]], rule)
        alpha[i, j], gamma[i, j] = a[0, n[i, j] - 1], g[0, n[i, j] - 1]
    return xr.Dataset(
        {
            "prefix_n": labelled(FRONTIER["prefix_n"], n),
            "prefix_alpha_halfwidth": labelled(FRONTIER["prefix_alpha_halfwidth"], alpha),
            "prefix_gamma_halfwidth": labelled(FRONTIER["prefix_gamma_halfwidth"], gamma),
            "prefix_seconds": labelled(FRONTIER["prefix_seconds"], n * per_realization),
            "prefix_count": labelled(FRONTIER["prefix_count"], counts),
        },
        coords={
            "cube_xi": labelled(FRONTIER["cube_xi"], cube_ds["xi"].values),
            "cube_lambda": labelled(FRONTIER["cube_lambda"], cube_ds["lambda"].values),
            "prefix_step": labelled(FRONTIER["prefix_step"], np.arange(PREFIX_POINTS)),
        },
        attrs={"prefix_cube_seconds": cube_seconds},
    )


def adaptive_prefix(scenario: Scenario, data_dir: str | Path) -> tuple[xr.Dataset | None, str]:
    """:func:`prefix_curve` of ``<data_dir>/cube.nc`` when it is an adaptive cube of ``scenario``.

    Returns
    -------
    tuple
        The curve (None when skipped) and a one-line note saying where it came from or why not.
    """
    from g2tom import store

    problem = store.stage_problem(data_dir, "cube", scenario)
    if problem:
        return None, f"prefix curve skipped: {problem}"
    path = store.stage_path(data_dir, "cube")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        if ds.attrs.get("ensemble") != "adaptive":
            return None, f"prefix curve skipped: {path} is a fixed ensemble (oxide.ensemble = \"fixed\")"
        cube_ds = ds[["resistance", "n_realizations"]].load()  # with the force coordinates
        rule_target = float(ds.attrs["rule_target_half_width"])
        config_hash = ds.attrs.get("config_hash")
    timings = Path(data_dir) / "timings.json"
    entry = json.loads(timings.read_text()).get("cube", {}) if timings.is_file() else {}
    if "seconds" not in entry or entry.get("config_hash") != config_hash:
        return None, f"prefix curve skipped: no cube time of {path} in {timings}"
    curve = prefix_curve(scenario, cube_ds, float(entry["seconds"]))
    curve.attrs["prefix_rule_target"] = rule_target
    return curve, (f"prefix curve of {path}: {int(curve['prefix_count'].sum())} realizations over "
                   f"{curve['prefix_count'].size} cells, cube time {entry['seconds']:.4g} s prorated")


def prefix_summary(prefix: xr.Dataset | None, note: str) -> dict[str, Any]:
    """JSON-ready summary of a prefix curve for the report: its note and, if any, its extremes."""
    if prefix is None:
        return {"note": note}
    first = {k: prefix[f"prefix_{k}_halfwidth"].isel(prefix_step=0) for k in ("alpha", "gamma")}
    last = {k: prefix[f"prefix_{k}_halfwidth"].isel(prefix_step=-1) for k in ("alpha", "gamma")}
    counts = prefix["prefix_count"].values
    return {
        "note": note, "cells": int(counts.size), "realizations": int(counts.sum()),
        "count_min": int(counts.min()), "count_median": float(np.median(counts)), "count_max": int(counts.max()),
        "first_n": int(prefix["prefix_n"].isel(prefix_step=0).min()),
        "alpha_first_max": float(first["alpha"].max()), "alpha_last_max": float(last["alpha"].max()),
        "gamma_first_max": float(first["gamma"].max()), "gamma_last_max": float(last["gamma"].max()),
        "cube_seconds": float(prefix.attrs["prefix_cube_seconds"]),
        "seconds_per_cell_max": float(prefix["prefix_seconds"].isel(prefix_step=-1).max()),
    }
