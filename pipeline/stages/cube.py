"""Stage 3: Greenwood's resistance over xi x lambda x delta x realization (the cube).

Reads the discrete spots of ``contact.nc`` and the oxide fields of ``oxide.nc``. A spot
conducts where its cell's ``psi < threshold`` (the stored float32 values); its resistance at
every load step follows Greenwood's Eqs. 11-15 (:mod:`pipeline.physics.constriction`), with
interaction weights ``cube.weights`` (spot radii, Eq. 13, or cell contact areas as in the
published code). With ``cube.model = "point"`` the exact point-interaction solve
(:mod:`pipeline.physics.point_model`) replaces the closed form, and ``oxide.film = "resistive"``
lets oxidized spots conduct through their film. The work is split over (lambda, realization chunk) dask tasks of about
``cube.chunk`` x n_xi masks (``cube.chunk`` fields when every xi is evaluated, proportionally
more when fewer fractions still need realizations); every entry's result is bit-identical
whatever the chunk size or scheduler.

The fields are not read from oxide.nc but regenerated inside each task from their seeds
(:class:`pipeline.stages.oxide.FieldSource`, bit-identical to oxide.nc's record), so the task
graph stays small and the ensemble can grow. ``oxide.ensemble = "fixed"`` computes
``oxide.n_realizations`` fields per lambda. ``"adaptive"`` grows every (xi, lambda) cell in
rounds: first ``oxide.min_realizations``, then ``oxide.batch`` more while the cell's fast-rule
95 % half-width of alpha (:mod:`pipeline.physics.ensemble`, exact for the geometric-mean fit on
the steps with F >= ``fits.min_force``) exceeds :data:`RULE_MARGIN` x ``oxide.target_half_width``, up to
``oxide.max_realizations``. A cell keeps the first prefix of realizations that meets the target,
so the result does not depend on the batch. The realization axis is padded to the largest count
(NaN, ``n_conducting`` -1) and ``n_realizations`` (xi, lambda) says how many entries are real.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import dask
import numpy as np
import xarray as xr

from pipeline import store
from pipeline.compute import ComputeOptions, compute
from pipeline.config import Scenario
from pipeline.physics import constriction, ensemble, point_model, spot_models
from pipeline.stages.oxide import FieldSource

__all__ = ["build", "run", "spot_maps"]

_TERMS = ("resistance", "resistance_self", "resistance_interaction", "n_conducting", "crop_bound")
#: Extra terms of the point model's iterative solve.
_SOLVER_TERMS = ("iterations", "residual", "error_estimate")
_LONG_NAMES = {
    "greenwood": "Greenwood constriction resistance R = R_self + R_int",
    "point": "point-interaction constriction resistance R = rho* / sum f (exact solve of M f = 1)",
}


def spot_maps(scenario: Scenario, contact: xr.Dataset) -> tuple[np.ndarray, np.ndarray, float]:
    """Spot radii and interaction weights per load step, and the cell pitch.

    Parameters
    ----------
    scenario
        Supplies ``cube.weights`` (``radius`` or ``area``).
    contact
        ``spot_radius`` and ``spot_area`` (delta, y, x) on evenly spaced cell centres ``x``.

    Returns
    -------
    tuple
        ``radius`` (m) and ``weights`` (m for ``cube.weights = radius``, m^2 for ``area``),
        both float64 of shape (delta, y, x), and the pitch of the cell centres ``x`` (m).
    """
    radius = np.asarray(contact["spot_radius"].transpose("delta", "y", "x").values, np.float64)
    if scenario.cube.weights == "radius":
        weights = radius
    else:
        weights = np.asarray(contact["spot_area"].transpose("delta", "y", "x").values, np.float64)
    x = np.asarray(contact["x"].values, np.float64)
    steps = np.diff(x)
    if x.size < 2 or not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
        raise ValueError("contact.nc: the cell centres x must be evenly spaced")
    return radius, weights, float(steps[0])


def _check_grids(contact: xr.Dataset, oxide: xr.Dataset) -> None:
    """Raise ValueError unless both files share one square grid of cell centres."""
    for axis in ("x", "y"):
        if contact[axis].size != oxide[axis].size or not np.allclose(
            contact[axis].values, oxide[axis].values, rtol=1e-9, atol=0
        ):
            raise ValueError(f"contact.nc and oxide.nc disagree on the cell centres '{axis}'")
    if not np.allclose(contact["x"].values, contact["y"].values, rtol=1e-9, atol=0):
        raise ValueError("contact.nc: the cell grid must be square (x and y identical)")


def _model(settings: dict[str, Any]) -> Any:
    """The resistance function of ``settings["model"]`` with the calling convention of
    :func:`constriction.resistance`: the point solve, Greenwood with films, or Greenwood."""
    film = settings["film_resistance"]
    if settings["model"] == "point":
        return functools.partial(
            point_model.resistance, film_resistance=film,
            solver_tolerance=settings["solver_tolerance"], max_iterations=settings["max_iterations"],
            criterion=settings["solver_criterion"],
        )
    if np.isfinite(film):
        return functools.partial(point_model.greenwood_resistance, film_resistance=film)
    return constriction.resistance


def _terms(settings: dict[str, Any]) -> tuple[str, ...]:
    """The per-entry terms the model of ``settings`` returns."""
    return _TERMS + _SOLVER_TERMS if settings["model"] == "point" else _TERMS


def _resistance(masks: np.ndarray, radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any],
                groups: np.ndarray | None = None) -> constriction.ChunkResult:
    """Resistance terms of a batch of conducting masks (batch, y, x) at every load step (map
    ``b`` with the spots ``radius[groups[b]]`` when ``groups`` is given)."""
    extra = {} if groups is None else {"groups": groups}
    return _model(settings)(
        masks, radius, weights, settings["pitch"], settings["rho"],
        settings["crops"], settings["tolerance"], settings["method"], **extra,
    )


def asperity_spots(settings: dict[str, Any], realizations: np.ndarray) -> np.ndarray:
    """The ``asperities`` discretization's spot radii of ``realizations``, (realization, delta, y, x), m.

    Realization ``k`` draws its asperity heights from its own stream
    (:func:`pipeline.physics.spot_models.heights`), held over every load step and shared by
    every (xi, lambda): the surface is one, the oxide fields vary.
    """
    seed, sigma, beta = settings["asperities"]
    separation = settings["separation"]
    n = separation.shape[-1]
    return np.stack([
        spot_models.asperity_radius(spot_models.heights(seed, int(k), n, sigma)[None], separation, beta)
        for k in realizations
    ])


def _chunk(
    psi: np.ndarray,
    threshold: np.ndarray,
    radius: np.ndarray,
    weights: np.ndarray,
    settings: dict[str, Any],
    realizations: np.ndarray | None = None,
) -> dict[str, Any]:
    """Greenwood terms of a chunk of fields.

    Parameters
    ----------
    psi
        Fields, float32, shape (lambda, realization, y, x).
    threshold
        Thresholds, float32, shape (xi, lambda, realization).
    radius, weights
        Spot radii (m) and interaction weights, shape (delta, y, x).
    settings
        ``pitch``, ``rho``, ``crops``, ``tolerance``, ``method`` (and for ``asperities`` spots
        what :func:`asperity_spots` needs).
    realizations
        The realization indices of the fields, for ``asperities`` spots (which then replace
        ``radius`` and ``weights``); None for spots shared by every realization.

    Returns
    -------
    dict
        The arrays of :data:`_TERMS`, shape (xi, lambda, delta, realization), and
        ``n_uncropped``.
    """
    n_xi, n_lam, n_real = threshold.shape
    n = psi.shape[-1]
    masks = psi[None] < threshold[..., None, None]
    groups = None
    if realizations is not None:  # per-realization spots: map (xi, lambda, r) takes group r
        radius = weights = asperity_spots(settings, realizations)
        groups = np.tile(np.arange(n_real), n_xi * n_lam)
    res = _resistance(masks.reshape(-1, n, n), radius, weights, settings, groups)
    out: dict[str, Any] = {
        name: getattr(res, name).reshape(n_xi, n_lam, n_real, -1).transpose(0, 1, 3, 2)
        for name in _terms(settings)
    }
    out["n_uncropped"] = res.n_uncropped
    return out


def _field_chunk(
    source: FieldSource, index: int, realizations: np.ndarray, xi_index: np.ndarray,
    radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any],
) -> dict[str, Any]:
    """Regenerate the fields of ``realizations`` at lambda number ``index`` and run :func:`_chunk`.

    Only the fractions ``xi_index`` are evaluated; returns the terms shaped (xi, delta, realization).
    """
    psi, threshold = source.fields(index, realizations)
    drawn = realizations if settings["spots"] == "asperities" else None
    out = _chunk(psi[None], threshold[xi_index][:, None], radius, weights, settings, drawn)
    return {k: (v[:, 0] if k in _terms(settings) else v) for k, v in out.items()}


def _rule(scenario: Scenario, force: np.ndarray, force_normalized: np.ndarray) -> dict[str, Any]:
    """The stopping rule's weights on the steps fitted by the fits stage, and its limits."""
    steps = np.flatnonzero(force >= scenario.fits.min_force)
    c_alpha = c_gamma = np.zeros(0)
    if steps.size >= 2:
        c_alpha, c_gamma = ensemble.fit_weights(np.log(force_normalized[steps]))
    return {"steps": steps, "c_alpha": c_alpha, "c_gamma": c_gamma,
            "z": ensemble.z_value(scenario.fits.confidence)}


def half_widths(resistance: np.ndarray, rule: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Fast-rule half-widths of alpha (relative) and gamma (absolute) for every prefix n.

    Parameters
    ----------
    resistance
        R in ohm, shape (xi, delta, realization) of one lambda.
    rule
        From :func:`_rule`.

    Returns
    -------
    tuple of numpy.ndarray
        Each (xi, realization): entry n - 1 is the half-width with the first n realizations.
    """
    if rule["steps"].size < 2:
        nan = np.full((resistance.shape[0], resistance.shape[-1]), np.nan)
        return nan, nan
    with np.errstate(divide="ignore"):
        log_r = np.log(resistance[:, rule["steps"], :])
    alpha = np.sinh(ensemble.prefix_half_width(ensemble.statistic(log_r, rule["c_alpha"]), rule["z"]))
    gamma = ensemble.prefix_half_width(ensemble.statistic(log_r, rule["c_gamma"]), rule["z"])
    return alpha, gamma


#: The fast rule stops a cell at this fraction of oxide.target_half_width: the first prefix whose
#: noisy half-width estimate dips below a target is optimistic, and the fits' percentile bootstrap
#: of a skewed statistic is a little wider (measured on the paper scenario: up to 1.11 x the fast
#: rule's half-width at the stopping count), so the confirmed intervals stay within the target.
RULE_MARGIN = 0.9


def _decide(scenario: Scenario, resistance: np.ndarray, rule: dict[str, Any]) -> list[int | None]:
    """Realizations each xi keeps once ``resistance`` (xi, delta, r) is known (None: more needed)."""
    ox = scenario.oxide
    computed = resistance.shape[-1]
    if ox.ensemble == "fixed":
        return [ox.n_realizations] * resistance.shape[0]
    alpha, _ = half_widths(resistance, rule)
    alpha = np.nan_to_num(alpha, nan=np.inf)
    out: list[int | None] = []
    for row in alpha:
        stop = ensemble.stop_count(row[None], RULE_MARGIN * ox.target_half_width, ox.min_realizations)
        if stop is None and computed >= ox.max_realizations:
            stop = ox.max_realizations
        out.append(stop)
    return out


def _compute(
    scenario: Scenario, source: FieldSource, radius: np.ndarray, weights: np.ndarray,
    settings: dict[str, Any], rule: dict[str, Any], options: ComputeOptions,
) -> tuple[list[list[dict[str, np.ndarray]]], int]:
    """Rounds of dask tasks over (lambda, realization chunk) until every (xi, lambda) has its count.

    Round one computes the first batch of every lambda (the fixed count, or
    ``oxide.min_realizations``); each further round adds ``oxide.batch`` realizations (at most up
    to the cap) to every lambda, for the fractions xi whose count is not decided yet (a field
    serves every xi, but an xi that reached its target costs nothing more). Realization r of a
    lambda always gets the same field, and an xi's count is the first prefix meeting the target,
    so neither the batch, the chunk size nor the workers change any result.

    Returns
    -------
    tuple
        ``[xi][lambda]`` the terms (delta, realization) of the kept realizations, and the number
        of entries recomputed uncropped.
    """
    ox = scenario.oxide
    n_xi, n_lam = source.xi.size, len(source.lambdas)
    first = ox.n_realizations if ox.ensemble == "fixed" else ox.min_realizations
    pieces: list[list[tuple[np.ndarray, dict[str, Any]]]] = [[] for _ in range(n_lam)]
    kept: list[list[int | None]] = [[None] * n_xi for _ in range(n_lam)]
    done = np.zeros(n_lam, int)
    want = np.full(n_lam, first)
    shared = dask.delayed(radius), dask.delayed(weights), dask.delayed(settings)
    uncropped = round_ = 0
    while open_cells := sum(k is None for row in kept for k in row):
        round_ += 1
        label = (f"cube round {round_} ({n_xi * n_lam} cells, {first} realizations each)" if round_ == 1 else
                 f"cube round {round_} (adaptive: {open_cells} of {n_xi * n_lam} cells still open)")
        tasks, owner = [], []
        for a in range(n_lam):
            active = np.array([z for z in range(n_xi) if kept[a][z] is None], int)
            if active.size == 0:
                continue
            # About cube.chunk * n_xi masks per task whatever the number of active fractions: the
            # resistance kernel works in fixed blocks of masks, so small tasks would waste them.
            chunk = scenario.cube.chunk * -(-n_xi // active.size)
            for start in range(done[a], want[a], chunk):
                block = np.arange(start, min(start + chunk, want[a]))
                tasks.append(dask.delayed(_field_chunk, pure=True)(source, a, block, active, *shared))
                owner.append((a, active))
        for (a, active), piece in zip(owner, compute(*tasks, options=options, label=label)):
            pieces[a].append((active, piece))
            uncropped += piece["n_uncropped"]
        for a in range(n_lam):
            active = [z for z in range(n_xi) if kept[a][z] is None]
            if not active:
                continue
            done[a] = want[a]
            resistance = np.stack([_joined(pieces[a], z, "resistance") for z in active])
            for z, count in zip(active, _decide(scenario, resistance, rule)):
                kept[a][z] = count
            want[a] = min(done[a] + ox.batch, ox.max_realizations)
    out = [
        [{name: _joined(pieces[a], z, name)[..., : kept[a][z]] for name in _terms(settings)} for a in range(n_lam)]
        for z in range(n_xi)
    ]
    return out, uncropped


def _joined(pieces: list[tuple[np.ndarray, dict[str, Any]]], z: int, name: str) -> np.ndarray:
    """One xi's term (delta, realization) of one lambda, from the pieces that evaluated it, in order."""
    return np.concatenate(
        [piece[name][int(np.flatnonzero(active == z)[0])] for active, piece in pieces if z in active], axis=-1
    )


def _padded(cells: list[list[dict[str, np.ndarray]]]) -> dict[str, np.ndarray]:
    """Stack the cells' terms into (xi, lambda, delta, realization), padded beyond each count.

    Floats are padded with NaN, counts (``n_conducting``, ``iterations``) with -1.
    """
    n_max = max(c["resistance"].shape[-1] for row in cells for c in row)
    out = {}
    for name in cells[0][0]:
        first = cells[0][0][name]
        fill = -1 if np.issubdtype(first.dtype, np.integer) else np.nan
        array = np.full((len(cells), len(cells[0]), first.shape[0], n_max), fill, dtype=first.dtype)
        for z, row in enumerate(cells):
            for a, c in enumerate(row):
                array[z, a, :, : c[name].shape[-1]] = c[name]
        out[name] = array
    return out


def _clean(radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any], n_drawn: int) -> dict[str, np.ndarray]:
    """The oxide-free surface, every spot conducting, on the whole window (exact), over delta.

    For ``asperities`` spots, over the first ``n_drawn`` realizations of the heights: the
    resistance of the mean conductance (open circuits conduct nothing), the self term of the
    mean self-conductance, and the probability of an open circuit.
    """
    n, n_delta = radius.shape[-1], radius.shape[0]
    whole = np.full(n_delta, n)
    call = functools.partial(_model(settings), pitch=settings["pitch"], rho=settings["rho"], crops=whole,
                             tolerance=0.0, method=settings["method"])
    if settings["spots"] != "asperities":
        res = call(np.ones((1, n, n), dtype=bool), radius, weights)
        return {"resistance": res.resistance[0], "self": res.resistance_self[0],
                "interaction": res.resistance_interaction[0], "open": np.zeros(n_delta), "n_drawn": 0}
    drawn = asperity_spots(settings, np.arange(n_drawn))
    res = call(np.ones((n_drawn, n, n), dtype=bool), drawn, drawn, groups=np.arange(n_drawn))
    rho = settings["rho"]
    with np.errstate(divide="ignore"):
        total = rho / np.mean(rho / res.resistance, axis=0)
        own = rho / np.mean(rho / res.resistance_self, axis=0)
    return {"resistance": total, "self": own, "interaction": total - own,
            "open": np.mean(np.isinf(res.resistance), axis=0), "n_drawn": n_drawn}


def _measured_crop_error(
    source: FieldSource, radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any],
    cropped: np.ndarray,
) -> float:
    """Largest relative change of ``R`` from cropping, over the first realization's entries."""
    n = radius.shape[-1]
    whole = dict(settings, crops=np.full(radius.shape[0], n), tolerance=0.0)
    first = np.arange(1)
    exact = np.stack(
        [_field_chunk(source, a, first, np.arange(source.xi.size), radius, weights, whole)["resistance"]
         for a in range(len(source.lambdas))],
        axis=1,
    )
    finite = np.isfinite(exact)
    if not finite.any():
        return 0.0
    return float(np.max(np.abs(cropped[..., :1][finite] / exact[finite] - 1.0)))


def _attrs(units: str, long_name: str, **extra: Any) -> dict[str, Any]:
    """CF-style attributes ``units`` and ``long_name`` plus any ``extra`` ones."""
    return {"units": units, "long_name": long_name, **extra}


def _dataset(
    scenario: Scenario, contact: xr.Dataset, oxide: xr.Dataset, out: dict[str, Any],
    clean: dict[str, Any], settings: dict[str, Any], measured: float,
    counts: np.ndarray, widths: tuple[np.ndarray, np.ndarray],
) -> xr.Dataset:
    """Wrap the computed arrays with coordinates and CF attributes."""
    dims = ("xi", "lambda", "delta", "realization")
    w_unit = "m" if scenario.cube.weights == "radius" else "m2"
    ox = scenario.oxide
    coords = {
        "xi": ("xi", oxide["xi"].values, _attrs("1", "nominal oxide fraction")),
        "lambda": ("lambda", oxide["lambda"].values,
                   _attrs("1", "normalized oxide correlation length l_O sqrt(eta)")),
        "delta": ("delta", contact["delta"].values, _attrs("m", "approach delta of the sphere tip")),
        "realization": ("realization", np.arange(out["resistance"].shape[-1]),
                        _attrs("1", "realization index of the random field")),
        "force": ("delta", contact["force"].values, _attrs("N", "normal force")),
        "force_normalized": ("delta", contact["force_normalized"].values,
                             _attrs("1", "normalized force F' = 2F / (E* sqrt(R* sigma^3))")),
    }
    is_open = np.isposinf(out["resistance"])
    clean_comment = ("the mean conductance (self-conductance) over the first "
                     f"{clean['n_drawn']} realizations of the asperity heights"
                     if scenario.contact.spots == "asperities" else "exact, every spot conducting")
    padding = "NaN beyond n_realizations(xi, lambda)"
    grid = ("xi", "lambda")
    data_vars = {
        "resistance": (dims, out["resistance"], _attrs(
            "ohm", _LONG_NAMES[scenario.cube.model],
            comment=f"+inf: open circuit (no conducting spot); {padding}")),
        "resistance_self": (dims, out["resistance_self"],
                            _attrs("ohm", "self term rho* / (2 sum phi a)", comment=padding)),
        "resistance_interaction": (dims, out["resistance_interaction"], _attrs(
            "ohm", f"interaction term rho* sum phi phi w w / d / (pi (sum phi w)^2), w in {w_unit}",
            comment=padding)),
        "n_conducting": (dims, out["n_conducting"].astype(np.int32),
                         _attrs("1", "number of conducting spots", comment="-1 beyond n_realizations(xi, lambda)")),
        "n_open": (("xi", "lambda", "delta"), is_open.sum(axis=-1).astype(np.int32),
                   _attrs("1", "number of open-circuit realizations (R = +inf)")),
        "n_realizations": (grid, counts.astype(np.int32), _attrs(
            "1", "realizations used at this (xi, lambda): the leading entries of realization",
            ensemble=ox.ensemble)),
        "rule_alpha_half_width": (grid, widths[0], _attrs(
            "1", "fast-rule relative half-width of alpha at n_realizations",
            method="sinh(z std(t_r) / sqrt(n)), t_r = least-squares log-alpha weights . log R_r")),
        "rule_gamma_half_width": (grid, widths[1], _attrs(
            "1", "fast-rule absolute half-width of gamma at n_realizations",
            method="z std(t_r) / sqrt(n), t_r = least-squares slope weights . log R_r")),
        "resistance_clean": ("delta", clean["resistance"],
                             _attrs("ohm", "resistance of the oxide-free surface", comment=clean_comment)),
        "resistance_clean_self": ("delta", clean["self"],
                                  _attrs("ohm", "self term of the oxide-free surface", comment=clean_comment)),
        "resistance_clean_interaction": ("delta", clean["interaction"],
                                         _attrs("ohm", "interaction term of the oxide-free surface")),
        "conductance_clean": ("delta", 1.0 / clean["resistance"],
                              _attrs("S", f"conductance of the oxide-free surface ({scenario.cube.model} model)")),
        "clean_open_probability": ("delta", clean["open"], _attrs(
            "1", "probability that the oxide-free surface is an open circuit (no touching asperity)")),
        "crop_cells": ("delta", np.asarray(settings["crops"], np.int32), _attrs(
            "1", "side of the centred square of cells kept at each approach")),
    }
    if "iterations" in out:
        data_vars["iterations"] = (dims, out["iterations"].astype(np.int32), _attrs(
            "1", "conjugate-gradient iterations of the point-model solve", comment="-1 beyond n_realizations(xi, lambda)"))
        data_vars["residual"] = (dims, out["residual"], _attrs(
            "1", "final relative residual of the point-model solve (Jacobi norm)", comment=padding))
        data_vars["error_estimate"] = (dims, out["error_estimate"], _attrs(
            "1", "estimated relative error of the point-model conductance (energy norm of the last step)",
            comment=padding))
    attrs = {
        "interaction_weights": scenario.cube.weights,
        "method": settings["method_used"],
        "crop_tolerance": settings["tolerance"],
        "crop_error_bound": float(np.nanmax(out["crop_bound"], initial=0.0)),
        "crop_error_measured": measured,
        "crop_error_measured_on": "all entries of the first realization, against the whole window",
        "n_uncropped": out["n_uncropped"],
        "n_open_total": int(is_open.sum()),
        "conducting_rule": "a spot conducts where spot_radius > 0 and psi < threshold (float32)",
        "fields": "regenerated in every task from SeedSequence(oxide.seed, spawn_key=(round(lambda * 1e6), realization))",
        "ensemble": ox.ensemble,
        "model": scenario.cube.model,
        "film": ox.film,
    }
    if ox.film == "resistive":
        attrs["film_resistance"] = ox.film_resistance
        attrs["conducting_rule"] = "every spot conducts; where psi >= threshold through the film"
    if "iterations" in out:
        attrs["solver_tolerance"] = scenario.cube.solver_tolerance
        attrs["solver_criterion"] = scenario.cube.solver_criterion
        measure = out["error_estimate"] if scenario.cube.solver_criterion == "error" else out["residual"]
        attrs["n_not_converged"] = int((measure > scenario.cube.solver_tolerance).sum())
    if ox.ensemble == "adaptive":
        attrs.update({
            "target_half_width": ox.target_half_width,
            "rule_target_half_width": RULE_MARGIN * ox.target_half_width,
            "min_realizations": ox.min_realizations,
            "max_realizations": ox.max_realizations,
            "stopping_rule": (
                f"per (xi, lambda), the smallest n >= min_realizations at which the fast-rule "
                f"alpha half-width is <= {RULE_MARGIN:g} x target_half_width, else max_realizations"
            ),
        })
    ds = xr.Dataset(data_vars, coords=coords, attrs=attrs)
    if ox.ensemble == "adaptive":  # the padding compresses to almost nothing
        for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
            ds[name].encoding.update(zlib=True, complevel=1)
    return ds


def build(
    scenario: Scenario,
    contact: xr.Dataset,
    oxide: xr.Dataset,
    options: ComputeOptions = ComputeOptions(progress=False),
    source: Any = None,
) -> xr.Dataset:
    """Compute the resistance cube of ``scenario`` from in-memory contact and oxide datasets.

    Parameters
    ----------
    scenario
        The validated scenario (sections ``material`` for rho*, ``cube``, ``oxide`` for the
        ensemble, ``fits.min_force`` and ``fits.confidence`` for the stopping rule).
    contact
        ``spot_radius`` and ``spot_area`` (delta, y, x), ``force``, ``force_normalized``.
    oxide
        The oxide stage's record: coordinates ``xi``, ``lambda``, ``y``, ``x``.
    options
        Where dask runs (see :func:`pipeline.compute.compute`).
    source
        Where the fields come from: anything with ``fields(lambda_index, realizations) ->
        (psi (r, y, x) float32, threshold (xi, r) float32)`` and ``lambdas``; default
        :class:`pipeline.stages.oxide.FieldSource` of ``scenario`` (fields regenerated from
        their seeds inside each task, never shipped in the task graph).

    Returns
    -------
    xarray.Dataset
        ``resistance``, its two terms and ``n_conducting`` (xi, lambda, delta, realization),
        ``n_open`` (xi, lambda, delta), ``n_realizations`` (lambda), the fast rule's half-widths
        (xi, lambda), the clean-surface terms and ``crop_cells`` (delta).
    """
    _check_grids(contact, oxide)
    source = FieldSource.of(scenario) if source is None else source
    radius, weights, pitch = spot_maps(scenario, contact)
    cube = scenario.cube
    film = scenario.oxide.film_resistance if scenario.oxide.film == "resistive" else np.inf
    whole_window = cube.model == "greenwood" and np.isfinite(film)
    settings = {
        "pitch": pitch,
        "rho": scenario.material.rho,
        "model": cube.model,
        "film_resistance": film,
        "solver_tolerance": cube.solver_tolerance,
        "max_iterations": cube.max_iterations,
        "solver_criterion": cube.solver_criterion,
        "crops": constriction.choose_crops(radius, weights, pitch, 0.0 if whole_window else cube.crop_tolerance),
        "tolerance": cube.crop_tolerance,
        "method": cube.method,
        "method_used": constriction.AUTO_METHOD if cube.method == "auto" else cube.method,
        "spots": scenario.contact.spots,
    }
    if scenario.contact.spots == "asperities":
        rough = scenario.roughness
        settings["asperities"] = (scenario.oxide.seed, rough.sigma, rough.beta)
        settings["separation"] = np.asarray(contact["spot_separation"].transpose("delta", "y", "x").values, np.float64)
    rule = _rule(scenario, contact["force"].values, contact["force_normalized"].values)
    cells, uncropped = _compute(scenario, source, radius, weights, settings, rule, options)
    counts = np.array([[c["resistance"].shape[-1] for c in row] for row in cells])
    widths = [[half_widths(c["resistance"][None], rule) for c in row] for row in cells]
    last = tuple(np.array([[w[k][0, -1] for w in row] for row in widths]) for k in (0, 1))
    out: dict[str, Any] = _padded(cells)
    out["n_uncropped"] = uncropped
    first = scenario.oxide.n_realizations if scenario.oxide.ensemble == "fixed" else scenario.oxide.min_realizations
    clean = _clean(radius, weights, settings, first)
    measured = _measured_crop_error(source, radius, weights, settings, out["resistance"])
    return _dataset(scenario, contact, oxide, out, clean, settings, measured, counts, last)


def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Read contact.nc and oxide.nc, build the cube and write ``<data_dir>/cube.nc`` atomically."""
    contact = store.read_stage(data_dir, "contact", scenario)
    oxide = store.read_stage(data_dir, "oxide", scenario)
    return store.write_dataset(build(scenario, contact, oxide, options), data_dir, "cube", scenario)
