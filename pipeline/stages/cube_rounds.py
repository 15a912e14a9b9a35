"""The cube's rounds: realizations per (xi, lambda) grown until each cell meets its target.

``oxide.ensemble = "fixed"`` computes ``oxide.n_realizations`` fields per lambda in one round.
``"adaptive"`` grows every (xi, lambda) cell in rounds: first ``oxide.min_realizations``, then
``compute.oxide_batch`` more while the cell's fast-rule 95 % half-width of alpha
(:mod:`g2tom.fitting.ensemble`, exact for the geometric-mean fit on the steps with
steps the fits stage fits, :meth:`g2tom.config.study_sections.Fits.fitted_loads`) exceeds :data:`RULE_MARGIN` x ``oxide.target_half_width``, up to
``oxide.max_realizations``; with ``fits.control_variate = "clean_share"`` the half-width of the
fits' own control-variate estimate, linearized (:func:`g2tom.fitting.ensemble.prefix_controlled_half_width`:
within 0.89-1.11 of the fits' bootstrap half-width, median 0.97, on the 108 cells of the paper
scenario). A cell keeps the first prefix of realizations that meets the target, so the result
does not depend on the batch.

With ``oxide.step_half_width`` (discrete spots) a cell whose alpha count is decided goes on until
the geometric mean of every fitted step meets that target too, the further realizations computed
only up to the heaviest step still short of it: the light steps, whose few touching spots scatter
most (their half-width is 2-4x alpha's at the same count, 1-2 ms a field where they are all a
field computes). Each step keeps its own first prefix meeting the target, at least alpha's count
and at least any heavier step's, so realization r is kept at a prefix of the steps.
"""

from __future__ import annotations

from typing import Any

import dask
import numpy as np

from g2tom.compute import ComputeOptions, compute
from g2tom.config import Scenario
from g2tom.fitting import ensemble
from g2tom.models.cube_settings import CubeSettings
from g2tom.scene import FieldSource

__all__ = ["RULE_MARGIN", "stopping_rule", "half_widths", "compute_cells", "padded"]


def stopping_rule(scenario: Scenario, force: np.ndarray, force_normalized: np.ndarray,
                  expected: np.ndarray | None = None) -> dict[str, Any]:
    """The stopping rule's weights on the steps fitted by the fits stage, and its limits;
    ``expected``: the control variate's exact expectation (xi, lambda), or None without it."""
    _, threshold, loads, _ = scenario.fits.fitted_loads(force, force_normalized)
    steps = np.flatnonzero(loads >= threshold)
    c_alpha = c_gamma = np.zeros(0)
    if steps.size >= 2:
        c_alpha, c_gamma = ensemble.fit_weights(np.log(force_normalized[steps]))
    return {"steps": steps, "c_alpha": c_alpha, "c_gamma": c_gamma,
            "z": ensemble.z_value(scenario.fits.confidence), "expected": expected}


def half_widths(resistance: np.ndarray, rule: dict[str, Any], clean_share: np.ndarray | None = None,
                expected: np.ndarray | None = None, first: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Fast-rule half-widths of alpha (relative) and gamma (absolute) for every prefix n.

    Parameters
    ----------
    resistance
        R in ohm, shape (xi, delta, realization) of one lambda.
    rule
        From :func:`stopping_rule`.
    clean_share
        The control variate (``fits.control_variate = "clean_share"``), shaped as ``resistance``:
        the half-widths of the fits' control-variate estimate, linearized
        (:func:`g2tom.fitting.ensemble.prefix_controlled_half_width`); None: plain.
    expected
        With ``clean_share``: its exact expectation for each xi of ``resistance``, shape (xi,).
    first
        Smallest prefix wanted with ``clean_share`` (shorter ones are NaN and cost nothing).

    Returns
    -------
    tuple of numpy.ndarray
        Each (xi, realization): entry n - 1 is the half-width with the first n realizations.
    """
    if rule["steps"].size < 2:
        nan = np.full((resistance.shape[0], resistance.shape[-1]), np.nan)
        return nan, nan
    if clean_share is not None:
        weights = np.stack([rule["c_alpha"], rule["c_gamma"]])
        alpha, gamma = np.stack([
            ensemble.prefix_controlled_half_width(r[rule["steps"]], x[rule["steps"]], p, weights, rule["z"], first)
            for r, x, p in zip(resistance, clean_share, expected)], axis=1)
        return np.sinh(alpha), gamma
    with np.errstate(divide="ignore"):
        log_r = np.log(resistance[:, rule["steps"], :])
    alpha, gamma = (ensemble.prefix_half_width(ensemble.statistic(log_r, w), rule["z"])
                    for w in (rule["c_alpha"], rule["c_gamma"]))
    return np.sinh(alpha), gamma


#: The fast rule stops a cell at this fraction of oxide.target_half_width: the first prefix whose
#: noisy half-width estimate dips below a target is optimistic, and the fits' percentile bootstrap
#: of a skewed statistic is a little wider (measured on the paper scenario: up to 1.11 x the fast
#: rule's half-width at the stopping count), so the confirmed intervals stay within the target.
RULE_MARGIN = 0.9


def _decide(scenario: Scenario, resistance: np.ndarray, rule: dict[str, Any],
            clean_share: np.ndarray | None = None, expected: np.ndarray | None = None,
            checked: int = 0) -> list[int | None]:
    """Realizations each xi keeps once ``resistance`` (xi, delta, r) is known (None: more needed);
    ``clean_share`` and ``expected``: the control variate, as in :func:`half_widths`; ``checked``:
    the prefixes an earlier round found short of the target (not evaluated again)."""
    ox = scenario.oxide
    computed = resistance.shape[-1]
    if ox.ensemble == "fixed":
        return [ox.n_realizations] * resistance.shape[0]
    alpha, _ = half_widths(resistance, rule, clean_share, expected, max(ox.min_realizations, checked + 1))
    alpha = np.nan_to_num(alpha, nan=np.inf)
    out: list[int | None] = []
    for row in alpha:
        stop = ensemble.stop_count(row[None], RULE_MARGIN * ox.target_half_width, ox.min_realizations)
        if stop is None and computed >= ox.max_realizations:
            stop = ox.max_realizations
        out.append(stop)
    return out


def _decide_steps(scenario: Scenario, resistance: np.ndarray, rule: dict[str, Any], n_alpha: int,
                  clean_share: np.ndarray | None = None, expected: float | None = None) -> np.ndarray:
    """Realizations each load step of one cell keeps (``oxide.step_half_width``), -1 where a fitted step
    still needs more.

    Parameters
    ----------
    resistance
        R in ohm of one (xi, lambda), shape (delta, r); NaN at a step beyond the realizations
        computed there (a prefix at every step).
    rule
        From :func:`stopping_rule` (its fitted steps and z).
    n_alpha
        The cell's count by alpha's target: every step keeps at least these.
    clean_share, expected
        The control variate shaped as ``resistance`` and its exact expectation, or None.

    Returns
    -------
    numpy.ndarray
        (delta,) int: at a fitted step the first prefix n >= ``n_alpha`` whose fast-rule relative
        half-width of the geometric mean is <= :data:`RULE_MARGIN` x the target (the cap where it
        was reached first); once every step is decided, made non-increasing with the load (a step
        keeps the largest count of the steps above it), so realization r is kept at a prefix of
        steps, the lightest first. Everything ``n_alpha`` without a step target.
    """
    ox = scenario.oxide
    counts = np.full(resistance.shape[0], n_alpha)
    if ox.step_half_width == 0:
        return counts
    for j in rule["steps"]:
        computed = int(np.count_nonzero(~np.isnan(resistance[j])))
        if clean_share is None:
            with np.errstate(divide="ignore"):
                t = np.log(resistance[j, :computed])
            width = ensemble.prefix_half_width(np.where(np.isfinite(t), t, np.nan), rule["z"])
        else:
            width = ensemble.prefix_controlled_half_width(resistance[j : j + 1, :computed],
                                                          clean_share[j : j + 1, :computed], expected,
                                                          np.ones(1), rule["z"], n_alpha)
        width = np.nan_to_num(np.sinh(width), nan=np.inf)
        stop = ensemble.stop_count(width[None], RULE_MARGIN * ox.step_half_width, n_alpha)
        if stop is None and computed >= ox.max_realizations:
            stop = ox.max_realizations
        counts[j] = -1 if stop is None else stop
    if (counts < 0).any():
        return counts
    return np.maximum.accumulate(counts[::-1])[::-1]


def _limit(alpha: int | None, steps: np.ndarray | None, n_delta: int) -> int:
    """Steps the next realizations of a cell are computed at: every step while alpha's count is open,
    else up to the heaviest step still open."""
    if alpha is None or steps is None:
        return n_delta
    return int(np.flatnonzero(steps < 0).max()) + 1


def _chunk(source: FieldSource, index: int, realizations: np.ndarray, xi_index: np.ndarray, radius: Any,
           weights: Any, settings: CubeSettings, *limit: int) -> dict[str, Any]:
    """A dask task of the cube: the contact model's unit of work (:meth:`g2tom.models.ContactModel.chunk`)."""
    return settings.contact_model.chunk(source, index, realizations, xi_index, radius, weights, settings, *limit)


def compute_cells(
    scenario: Scenario, source: FieldSource, radius: np.ndarray, weights: np.ndarray,
    settings: CubeSettings, rule: dict[str, Any], options: ComputeOptions,
) -> tuple[list[list[dict[str, np.ndarray]]], np.ndarray, np.ndarray | None, int]:
    """Rounds of dask tasks over (lambda, realization chunk) until every (xi, lambda) has its count.

    Round one computes the first batch of every lambda (the fixed count, or
    ``oxide.min_realizations``); each further round adds ``compute.oxide_batch`` realizations (at most up
    to the cap) to every lambda, for the fractions xi whose count is not decided yet (a field
    serves every xi, but an xi that reached its target costs nothing more). Realization r of a
    lambda always gets the same field, and an xi's count is the first prefix meeting the target,
    so neither the batch, the chunk size nor the workers change any result. With
    ``oxide.step_half_width`` a cell whose alpha count is decided goes on at its light steps only
    (:func:`_decide_steps`; discrete spots compute the steps below a limit).

    Returns
    -------
    tuple
        ``[xi][lambda]`` the terms (delta, realization) of the kept realizations (NaN, counts -1,
        at a step beyond its own count), the counts by alpha's target (xi, lambda), the counts of
        every step (xi, lambda, delta) or None without a step target, and the number of entries
        recomputed uncropped.
    """
    ox = scenario.oxide
    n_xi, n_lam, n_delta = source.xi.size, len(source.lambdas), len(settings.crops)
    per_step = ox.ensemble == "adaptive" and ox.step_half_width > 0
    first = ox.n_realizations if ox.ensemble == "fixed" else ox.min_realizations
    pieces: list[list[tuple[np.ndarray, dict[str, Any]]]] = [[] for _ in range(n_lam)]
    kept: list[list[int | None]] = [[None] * n_xi for _ in range(n_lam)]
    steps: list[list[np.ndarray | None]] = [[None] * n_xi for _ in range(n_lam)]
    done = np.zeros(n_lam, int)
    want = np.full(n_lam, first)
    shared = dask.delayed(radius), dask.delayed(weights), dask.delayed(settings)
    source_key = dask.delayed(source)  # one key, however many tasks read it (it may hold oxide.nc's record)
    uncropped = round_ = 0

    def is_open(a: int, z: int) -> bool:
        return kept[a][z] is None or (steps[a][z] is not None and (steps[a][z] < 0).any())

    while open_cells := sum(is_open(a, z) for a in range(n_lam) for z in range(n_xi)):
        round_ += 1
        label = (f"cube round {round_} ({n_xi * n_lam} cells, {first} realizations each)" if round_ == 1 else
                 f"cube round {round_} (adaptive: {open_cells} of {n_xi * n_lam} cells still open)")
        tasks, owner = [], []
        for a in range(n_lam):
            limits: dict[int, list[int]] = {}
            for z in range(n_xi):
                if is_open(a, z):
                    limits.setdefault(_limit(kept[a][z], steps[a][z], n_delta), []).append(z)
            for limit, members in sorted(limits.items(), reverse=True):
                active = np.array(members, int)
                # About compute.cube_chunk * n_xi masks per task whatever the number of active fractions: the
                # resistance kernel works in fixed blocks of masks, so small tasks would waste them.
                chunk = scenario.compute.cube_chunk * -(-n_xi // active.size)
                below = () if limit == n_delta else (limit,)
                for start in range(done[a], want[a], chunk):
                    block = np.arange(start, min(start + chunk, want[a]))
                    tasks.append(dask.delayed(_chunk, pure=True)(source_key, a, block, active, *shared, *below))
                    owner.append((a, active))
        for (a, active), piece in zip(owner, compute(*tasks, options=options, label=label)):
            pieces[a].append((active, piece))
            uncropped += piece["n_uncropped"]
        for a in range(n_lam):
            active = [z for z in range(n_xi) if is_open(a, z)]
            if not active:
                continue
            checked, done[a] = done[a], want[a]
            undecided = [z for z in active if kept[a][z] is None]
            if undecided:
                resistance = np.stack([_joined(pieces[a], z, "resistance") for z in undecided])
                share = (np.stack([_joined(pieces[a], z, "clean_share") for z in undecided])
                         if settings.control_variate else None)
                expected = None if share is None else rule["expected"][undecided, a]
                for z, count in zip(undecided, _decide(scenario, resistance, rule, share, expected, checked)):
                    kept[a][z] = count
            for z in active:
                if per_step and kept[a][z] is not None:
                    share, expected = ((_joined(pieces[a], z, "clean_share"), rule["expected"][z, a])
                                       if settings.control_variate else (None, None))
                    steps[a][z] = _decide_steps(scenario, _joined(pieces[a], z, "resistance"), rule, kept[a][z],
                                                share, expected)
            want[a] = min(done[a] + scenario.compute.oxide_batch, ox.max_realizations)
    counts = np.array(kept, int).T
    if not per_step:
        out = [[{name: _joined(pieces[a], z, name)[..., : kept[a][z]] for name in settings.contact_model.terms(settings)}
                for a in range(n_lam)] for z in range(n_xi)]
        return out, counts, None, uncropped
    step_counts = np.array(steps, int).transpose(1, 0, 2)
    out = [[_kept_steps({name: _joined(pieces[a], z, name) for name in settings.contact_model.terms(settings)}, step_counts[z, a])
            for a in range(n_lam)] for z in range(n_xi)]
    return out, counts, step_counts, uncropped


def _kept_steps(cell: dict[str, np.ndarray], counts: np.ndarray) -> dict[str, np.ndarray]:
    """A cell's terms (delta, realization) cut to its lightest step's count, each step blanked (NaN,
    counts -1) beyond its own ``counts`` (delta,)."""
    beyond = np.arange(int(counts.max()))[None, :] >= counts[:, None]
    out = {}
    for name, values in cell.items():
        values = values[..., : int(counts.max())].copy()
        values[beyond] = -1 if np.issubdtype(values.dtype, np.integer) else np.nan
        out[name] = values
    return out


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
