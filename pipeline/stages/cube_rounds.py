"""The cube's rounds: realizations per (xi, lambda) grown until each cell meets its target.

``oxide.ensemble = "fixed"`` computes ``oxide.n_realizations`` fields per lambda in one round.
``"adaptive"`` grows every (xi, lambda) cell in rounds: first ``oxide.min_realizations``, then
``oxide.batch`` more while the cell's fast-rule 95 % half-width of alpha
(:mod:`pipeline.fitting.ensemble`, exact for the geometric-mean fit on the steps with
steps the fits stage fits, :func:`pipeline.stages.fit_steps.fit_range`) exceeds :data:`RULE_MARGIN` x ``oxide.target_half_width``, up to
``oxide.max_realizations``; with ``fits.control_variate = "clean_share"`` the half-width of the
statistic adjusted by the control (its residual after the regression on the control's statistic). A cell keeps the first prefix of realizations that meets the
target, so the result does not depend on the batch.
"""

from __future__ import annotations

from typing import Any

import dask
import numpy as np

from pipeline.compute import ComputeOptions, compute
from pipeline.config import Scenario
from pipeline.fitting import ensemble
from pipeline.stages.cube_chunks import CubeSettings, field_chunk, terms
from pipeline.stages.fit_steps import fit_range
from pipeline.scene import FieldSource

__all__ = ["RULE_MARGIN", "stopping_rule", "half_widths", "compute_cells", "padded"]

def stopping_rule(scenario: Scenario, force: np.ndarray, force_normalized: np.ndarray) -> dict[str, Any]:
    """The stopping rule's weights on the steps fitted by the fits stage, and its limits."""
    _, threshold, loads, _ = fit_range(scenario, force, force_normalized)
    steps = np.flatnonzero(loads >= threshold)
    c_alpha = c_gamma = np.zeros(0)
    if steps.size >= 2:
        c_alpha, c_gamma = ensemble.fit_weights(np.log(force_normalized[steps]))
    return {"steps": steps, "c_alpha": c_alpha, "c_gamma": c_gamma,
            "z": ensemble.z_value(scenario.fits.confidence)}


def half_widths(resistance: np.ndarray, rule: dict[str, Any],
                clean_share: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fast-rule half-widths of alpha (relative) and gamma (absolute) for every prefix n.

    Parameters
    ----------
    resistance
        R in ohm, shape (xi, delta, realization) of one lambda.
    rule
        From :func:`stopping_rule`.
    clean_share
        The control variate (``fits.control_variate = "clean_share"``), shaped as ``resistance``:
        the statistics' half-widths after their regression on the same weights of it
        (:func:`pipeline.fitting.ensemble.prefix_controlled_half_width`); None: plain.

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

    def width(weights: np.ndarray) -> np.ndarray:
        t = ensemble.statistic(log_r, weights)
        if clean_share is None:
            return ensemble.prefix_half_width(t, rule["z"])
        u = ensemble.statistic(clean_share[:, rule["steps"], :], weights)
        return ensemble.prefix_controlled_half_width(t, u, rule["z"])

    return np.sinh(width(rule["c_alpha"])), width(rule["c_gamma"])


#: The fast rule stops a cell at this fraction of oxide.target_half_width: the first prefix whose
#: noisy half-width estimate dips below a target is optimistic, and the fits' percentile bootstrap
#: of a skewed statistic is a little wider (measured on the paper scenario: up to 1.11 x the fast
#: rule's half-width at the stopping count), so the confirmed intervals stay within the target.
RULE_MARGIN = 0.9


def _decide(scenario: Scenario, resistance: np.ndarray, rule: dict[str, Any],
            clean_share: np.ndarray | None = None) -> list[int | None]:
    """Realizations each xi keeps once ``resistance`` (xi, delta, r) is known (None: more needed);
    ``clean_share``: the control variate, as in :func:`half_widths`."""
    ox = scenario.oxide
    computed = resistance.shape[-1]
    if ox.ensemble == "fixed":
        return [ox.n_realizations] * resistance.shape[0]
    alpha, _ = half_widths(resistance, rule, clean_share)
    alpha = np.nan_to_num(alpha, nan=np.inf)
    out: list[int | None] = []
    for row in alpha:
        stop = ensemble.stop_count(row[None], RULE_MARGIN * ox.target_half_width, ox.min_realizations)
        if stop is None and computed >= ox.max_realizations:
            stop = ox.max_realizations
        out.append(stop)
    return out


def compute_cells(
    scenario: Scenario, source: FieldSource, radius: np.ndarray, weights: np.ndarray,
    settings: CubeSettings, rule: dict[str, Any], options: ComputeOptions,
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
    source_key = dask.delayed(source)  # one key, however many tasks read it (it may hold oxide.nc's record)
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
                tasks.append(dask.delayed(field_chunk, pure=True)(source_key, a, block, active, *shared))
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
            share = (np.stack([_joined(pieces[a], z, "clean_share") for z in active]) if settings.control_variate
                     else None)
            for z, count in zip(active, _decide(scenario, resistance, rule, share)):
                kept[a][z] = count
            want[a] = min(done[a] + ox.batch, ox.max_realizations)
    out = [
        [{name: _joined(pieces[a], z, name)[..., : kept[a][z]] for name in terms(settings)} for a in range(n_lam)]
        for z in range(n_xi)
    ]
    return out, uncropped


def _joined(pieces: list[tuple[np.ndarray, dict[str, Any]]], z: int, name: str) -> np.ndarray:
    """One xi's term (delta, realization) of one lambda, from the pieces that evaluated it, in order."""
    return np.concatenate(
        [piece[name][int(np.flatnonzero(active == z)[0])] for active, piece in pieces if z in active], axis=-1
    )


def padded(cells: list[list[dict[str, np.ndarray]]]) -> dict[str, np.ndarray]:
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
