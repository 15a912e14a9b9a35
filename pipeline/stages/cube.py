"""Stage 3: Greenwood's resistance over xi x lambda x delta x realization (the cube).

Reads the discrete spots of ``contact.nc`` and the oxide fields of ``oxide.nc``. A spot
conducts where its cell's ``psi < threshold`` (the stored float32 values); its resistance at
every load step follows Greenwood's Eqs. 11-15 (:mod:`g2tom.physics.constriction`), with
interaction weights ``cube.weights`` (spot radii, Eq. 13, or cell contact areas as in the
published code). With ``cube.model = "point"`` the exact point-interaction solve
(:mod:`g2tom.physics.point_model`) replaces the closed form, and ``oxide.film = "resistive"``
lets oxidized spots conduct through their film. The work is split over (lambda, realization chunk) dask tasks
(the contact model's unit of work, :meth:`g2tom.models.ContactModel.chunk`) of about
``compute.cube_chunk`` x n_xi masks (``compute.cube_chunk`` fields when every xi is evaluated, proportionally
more when fewer fractions still need realizations); every entry's result is bit-identical
whatever the chunk size or scheduler.

The fields oxide.nc records (the fixed ensemble, or the adaptive ensemble's first batch) are
served from the record when it is at most :data:`g2tom.stages.oxide.RECORD_BYTES`; every other
field is regenerated inside its task from its seed (:class:`g2tom.scene.FieldSource`,
bit-identical to the record), so memory stays bounded and the ensemble can grow. ``oxide.ensemble = "fixed"`` computes
``oxide.n_realizations`` fields per lambda. ``"adaptive"`` grows every (xi, lambda) cell in
rounds (:mod:`g2tom.stages.cube_rounds`). The realization axis is padded to the largest count
(NaN, ``n_conducting`` -1) and ``n_realizations`` (xi, lambda) says how many entries are real; with
``oxide.step_half_width`` the light steps hold more, ``step_realizations`` (xi, lambda, delta).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom import store
from g2tom.before_work.domains import resolved
from g2tom.compute import ComputeOptions, single_threaded
from g2tom.config import Scenario
from g2tom.physics.crops import choose_crops
from g2tom.physics.interaction import AUTO_METHOD
from g2tom.physics import oxide_field
from g2tom.physics.lattice import SQUARE_LATTICE_CONSTANT
from g2tom.physics.oxide_marginal import clean_probability
from g2tom.models import contact_model
from g2tom.models.cube_settings import CubeSettings
from g2tom.stages.cube_dataset import dataset
from g2tom.stages.cube_rounds import compute_cells, half_widths, padded, stopping_rule
from g2tom.scene import bands
from g2tom.stages.oxide import RecordedFields

__all__ = ["build", "run", "spot_maps", "work_settings", "clean_conductances", "CLEAN_MODELS"]


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


#: The clean surface's conductance by each model, for Barber's check: (name, model, lattice constant).
CLEAN_MODELS = (("greenwood", "greenwood", 0.0), ("point", "point", 0.0),
                ("point_lattice", "point", SQUARE_LATTICE_CONSTANT))


def _clean_models(radius: Any, weights: Any, settings: CubeSettings, n_drawn: int,
                  known: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The oxide-free conductance (S, over delta) of every model of :data:`CLEAN_MODELS` with the
    run's spots, solved tightly (NaN where the model does not apply:
    :meth:`g2tom.models.ContactModel.clean_conductance`); the models in ``known`` are taken from it."""
    out = dict(known)
    for name, kind, constant in CLEAN_MODELS:
        if name not in out:
            out[name] = settings.contact_model.clean_conductance(radius, weights, settings, n_drawn, kind, constant)
    return out


def work_settings(scenario: Scenario, contact: xr.Dataset) -> tuple[np.ndarray, np.ndarray, CubeSettings]:
    """Spot radii and weights (delta, y, x) of ``contact`` and the settings every task of the cube reads
    (as the contact model takes them: :meth:`g2tom.models.ContactModel.cube_spots`)."""
    radius, weights, pitch = spot_maps(scenario, contact)
    cube = scenario.cube
    film = scenario.oxide.film_resistance if scenario.oxide.film == "resistive" else np.inf
    whole_window = cube.model == "greenwood" and np.isfinite(film)
    asperities = separation = None
    if scenario.contact.spots == "asperities":
        rough = scenario.roughness
        asperities = (scenario.oxide.seed, rough.sigma, rough.beta)
        separation = np.asarray(contact["spot_separation"].transpose("delta", "y", "x").values, np.float64)
    settings = CubeSettings(
        pitch=pitch,
        rho=scenario.material.rho,
        model=cube.model,
        film_resistance=film,
        solver_tolerance=cube.solver_tolerance,
        max_iterations=cube.max_iterations,
        solver_criterion=cube.solver_criterion,
        crops=choose_crops(radius, weights, pitch, 0.0 if whole_window else cube.crop_tolerance),
        tolerance=cube.crop_tolerance,
        method=scenario.compute.interaction_sum,
        method_used=AUTO_METHOD if scenario.compute.interaction_sum == "auto" else scenario.compute.interaction_sum,
        spots=scenario.contact.spots,
        lattice_constant=cube.lattice_constant,
        asperities=asperities,
        separation=separation,
        spot_rule=scenario.oxide.spot_rule,
        control_variate=scenario.fits.control_variate == "clean_share",
        contact_model=contact_model(scenario),
    )
    return settings.contact_model.cube_spots(contact, radius, weights, settings)


def _clean_draws(scenario: Scenario) -> int:
    """Realizations of the asperity heights behind the clean surface: the ensemble's first round."""
    ox = scenario.oxide
    return ox.n_realizations if ox.ensemble == "fixed" else ox.min_realizations


def clean_conductances(scenario: Scenario, contact: xr.Dataset,
                       known: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """The oxide-free conductance (S, over delta) of ``contact``'s spots by every model of
    :data:`CLEAN_MODELS`, for Barber's check against ``contact["barber_conductance"]`` (those
    in ``known`` are taken from it)."""
    radius, weights, settings = work_settings(scenario, contact)
    return _clean_models(radius, weights, settings, _clean_draws(scenario), known or {})


def expected_clean_share(scenario: Scenario) -> np.ndarray:
    """The expectation of every (xi, lambda)'s control variate ``clean_share``: the probability that a
    point of the field is clean at the float32 theoretical threshold, (xi, lambda)."""
    thresholds = oxide_field.theoretical_threshold(np.asarray(scenario.oxide.xi, float)).astype(np.float32)
    return np.array([[clean_probability(band.weight, float(t)) for band in bands(scenario)] for t in thresholds])


@single_threaded
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
        The scenario (sections ``material`` for rho*, ``cube``, ``oxide`` for the ensemble,
        ``fits.min_force`` and ``fits.confidence`` for the stopping rule; resolved first where it
        is not: :func:`g2tom.before_work.domains.resolved`).
    contact
        ``spot_radius`` and ``spot_area`` (delta, y, x), ``force``, ``force_normalized``.
    oxide
        The oxide stage's record: coordinates ``xi``, ``lambda``, ``y``, ``x``.
    options
        Where dask runs (see :func:`g2tom.compute.compute`).
    source
        Where the fields come from: anything with ``fields(lambda_index, realizations) ->
        (psi (r, y, x) float32, threshold (xi, r) float32)`` and ``lambdas``; default
        :class:`g2tom.stages.oxide.RecordedFields` of ``scenario`` and ``oxide`` (the record
        where it holds the field, else regenerated from its seed inside the task).

    Returns
    -------
    xarray.Dataset
        ``resistance``, its two terms and ``n_conducting`` (xi, lambda, delta, realization),
        ``n_open`` (xi, lambda, delta), ``n_realizations`` (xi, lambda; with
        ``oxide.step_half_width`` also ``step_realizations``, xi, lambda, delta), the fast rule's
        half-widths (xi, lambda), the clean-surface terms and ``crop_cells`` (delta).
    """
    scenario = resolved(scenario)
    _check_grids(contact, oxide)
    source = RecordedFields.of(scenario, oxide) if source is None else source
    radius, weights, settings = work_settings(scenario, contact)
    expected = expected_clean_share(scenario) if settings.control_variate else None
    rule = stopping_rule(scenario, contact["force"].values, contact["force_normalized"].values, expected)
    cells, counts, step_counts, uncropped = compute_cells(scenario, source, radius, weights, settings, rule, options)
    widths = [[half_widths(c["resistance"][None, ..., :n], rule, c["clean_share"][None, ..., :n], expected[z, a, None], n)
               if settings.control_variate else half_widths(c["resistance"][None, ..., :n], rule)
               for a, (c, n) in enumerate(zip(row, n_row))] for z, (row, n_row) in enumerate(zip(cells, counts))]
    last = tuple(np.array([[w[k][0, -1] for w in row] for row in widths]) for k in (0, 1))
    out: dict[str, Any] = padded(cells)
    out["n_uncropped"] = uncropped
    if step_counts is not None:
        out["step_realizations"] = step_counts
    if settings.control_variate:
        out["clean_share_expected"] = expected
    clean = settings.contact_model.clean(radius, weights, settings, _clean_draws(scenario))
    insulating_greenwood = scenario.cube.model == "greenwood" and scenario.oxide.film == "insulating"
    clean["models"] = clean_conductances(
        scenario, contact, {"greenwood": 1.0 / clean["resistance"]} if insulating_greenwood else None)
    measured = settings.contact_model.crop_error(source, radius, weights, settings, out["resistance"])
    return dataset(scenario, contact, oxide, out, clean, settings, measured, counts, last)


@single_threaded
def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Read contact.nc and oxide.nc, build the cube and write ``<data_dir>/cube.nc`` atomically."""
    contact = store.read_stage(data_dir, "contact", scenario)
    oxide = store.read_stage(data_dir, "oxide", scenario)
    return store.write_dataset(build(scenario, contact, oxide, options), data_dir, "cube", scenario)
