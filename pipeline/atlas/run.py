"""``g2tom atlas``: the chain contact -> oxide -> cube -> fits on every scene of the design.

One scene is one task: on a ``dask.distributed`` cluster (a local one of ``--workers``
single-threaded processes, or ``--scheduler ADDRESS``) each worker runs whole scenes, each
single-threaded inside, so the results do not depend on the cluster (the same bits on one
process or many). Every finished scene is written at once, atomically, to
``<data>/atlas/scenes/<name>.nc`` with its configuration hash: a killed atlas continues with the
scenes not written yet. When all are there, ``<data>/atlas/atlas.nc`` gathers them over the
dimension ``scene``.

``atlas.nc`` holds, per scene: ``mu``, ``Pi``, ``heldout`` (1: never used in a fit),
``n_cells``, ``wall_seconds``; per (scene, xi, lambda): ``alpha``, ``gamma``, their intervals
``alpha_ci`` / ``gamma_ci`` (bound), ``n_realizations``; per (scene, xi, lambda, step): the fitted
reduction ``resistance_normalized`` (R'); per (scene, step): ``force_normalized`` (F') and
``fitted``; the clean fit ``alpha_clean`` / ``gamma_clean`` per scene; the fits stage's curve model
``curve_coefficients`` (scene, xi, lambda, power), ``curve_order``, ``curve_max_error``, ``curve_within``.
"""

from __future__ import annotations

import dataclasses
import functools
import sys
import time
from contextlib import ExitStack
from pathlib import Path

import xarray as xr

from g2tom.atlas.design import (AtlasDesign, Scene, SceneEstimate, design_scenes, format_atlas_plan, plan_atlas,
                                   scene_scenario, schedule)
from g2tom.atlas.schema import ATLAS, SCALARS
from g2tom.compute import ComputeOptions, in_turn
from g2tom.config import ConfigError, Loading, Scenario
from g2tom.store import atomic_path, provenance

__all__ = ["scene_dataset", "scene_path", "run_atlas", "longest_first", "ATLAS_FILE"]

ATLAS_FILE = "atlas.nc"
_ONE = ComputeOptions(workers=1, progress=False)


def scene_path(data_dir: str | Path, scene: Scene) -> Path:
    """Where a scene's result lives."""
    return Path(data_dir) / "atlas" / "scenes" / f"{scene.name}.nc"


def scene_dataset(base: Scenario, scene: Scene, loading: Loading | None = None,
                  options: ComputeOptions = _ONE) -> xr.Dataset:
    """Run the chain on one scene in memory, single-threaded unless ``options`` say otherwise (a
    scene that runs alone); its slice of ``atlas.nc`` (``loading``: see
    :func:`g2tom.atlas.design.scene_scenario`). The result does not depend on ``options``."""
    from g2tom.before_work.domains import resolve
    from g2tom.stages import contact, cube, fits, oxide
    from g2tom.stages.schema import SURROGATE_COORDINATES

    start = time.perf_counter()
    scenario = resolve(scene_scenario(base, scene, loading))
    c = contact.build(scenario, options)
    k = cube.build(scenario, c, oxide.build(scenario, options), options)
    f = fits.build(scenario, k)
    grid = ("xi", "lambda")

    def take(name: str, dims: tuple[str, ...]) -> tuple:
        return dims, f[name].transpose(*dims).values, dict(f[name].attrs)

    def own(name: str, data: object) -> tuple:
        """``(dims, data, attrs)`` of one of the atlas's own variables (:data:`g2tom.atlas.schema.ATLAS`)."""
        var = ATLAS[name]
        return var.dims, data, var.attrs(reduction=scenario.fits.reduction)

    reduced = f[f"{scenario.fits.reduction}_normalized"].transpose("xi", "lambda", "delta").values
    reduced_ci = f[f"{scenario.fits.reduction}_normalized_ci"].transpose("xi", "lambda", "delta", "bound").values
    ds = xr.Dataset(
        {
            **{name: take(name, grid) for name in ("alpha", "gamma", "n_realizations")},
            **{name: take(name, grid + ("bound",)) for name in ("alpha_ci", "gamma_ci")},
            **{name: take(name, ()) for name in ("alpha_clean", "gamma_clean")},
            # the curve model of the fits stage (ln R' polynomial in ln F')
            **{name: take(name, grid) for name in ("curve_order", "curve_max_error", "curve_within")},
            "curve_coefficients": take("curve_coefficients", grid + ("power",)),
            "resistance_normalized": own("resistance_normalized", reduced),
            "resistance_normalized_ci": own("resistance_normalized_ci", reduced_ci),
            "open_probability": (grid + ("step",), f["open_probability"].transpose("xi", "lambda", "delta").values,
                                 dict(f["open_probability"].attrs)),
            "resistance_clean_normalized": own("resistance_clean_normalized", f["resistance_clean_normalized"].values),
            "force_normalized": own("force_normalized", k["force_normalized"].values),
            "fitted": own("fitted", f["fitted"].values),
        },
        coords={name: (name, f[name].values, SURROGATE_COORDINATES[name].attrs())
                for name in grid},
    )
    ds = ds.assign_coords(bound=own("bound", f["bound"].values), power=own("power", f["power"].values))
    scalars = {"mu": scene.mu, "Pi": scene.Pi, "heldout": int(scene.heldout), "n_cells": scenario.n_cells,
               "wall_seconds": time.perf_counter() - start}
    for name in SCALARS:
        ds[name] = xr.DataArray(scalars[name], attrs=ATLAS[name].attrs())
    ds.attrs.update(provenance(scene_scenario(base, scene, loading), "fits"))
    ds.attrs.update(scene=scene.name, title=f"g2tom atlas scene {scene.name}", stage="atlas scene")
    return ds


def _done(base: Scenario, scene: Scene, data_dir: Path, loading: Loading | None = None) -> bool:
    """Whether the scene's file is there, readable and of this configuration."""
    path = scene_path(data_dir, scene)
    if not path.is_file():
        return False
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return ds.attrs.get("config_hash") == scene_scenario(base, scene, loading).config_hash("fits")
    except (OSError, ValueError, RuntimeError):
        return False


def _run_scene(base: Scenario, scene: Scene, data_dir: Path, loading: Loading | None = None,
               options: ComputeOptions = _ONE) -> tuple[str, float]:
    """The task: one scene, written atomically; its name and wall time."""
    ds = scene_dataset(base, scene, loading, options)
    with atomic_path(scene_path(data_dir, scene)) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    return scene.name, float(ds["wall_seconds"])


#: The invariance check's twin: the middle design scene again with sigma x TWIN_SCALE and
#: R* / TWIN_SCALE (equal mu and Pi, other dimensions); never fitted.
TWIN_SCALE = 2.0


def twin_base(base: Scenario) -> Scenario:
    """``base`` with sigma x :data:`TWIN_SCALE` and R* / :data:`TWIN_SCALE`: a scene of it has the
    same (mu, Pi) as the scene of ``base`` but other dimensions."""
    return dataclasses.replace(
        base, roughness=dataclasses.replace(base.roughness, sigma=base.roughness.sigma * TWIN_SCALE),
        indenter=dataclasses.replace(base.indenter, radius=base.indenter.radius / TWIN_SCALE))


def _twin(scenes: list[Scene]) -> tuple[Scene, Scene]:
    """The design scene checked for invariance (the middle one) and its twin: the same groups and
    role, so measured alike (a held-out scene's tighter ensemble would make the check the two
    ensembles' noise); never among the scenes fitted or judged."""
    design = [s for s in scenes if not s.heldout]
    scene = design[len(design) // 2]
    return scene, dataclasses.replace(scene, name=f"t{scene.name}")


def _invariance(scene_ds: xr.Dataset, twin_ds: xr.Dataset) -> float:
    """Largest |ln R'_twin - ln R'_scene| over the cells and fitted steps of two scenes of equal groups."""
    import numpy as np

    fitted = scene_ds["fitted"].values.astype(bool)
    a = scene_ds["resistance_normalized"].values[..., fitted]
    b = twin_ds["resistance_normalized"].values[..., fitted]
    return float(np.max(np.abs(np.log(b) - np.log(a))))


def _gather(base: Scenario, scenes: list[Scene], data_dir: Path) -> Path:
    """``atlas.nc`` from the scene files, over the dimension ``scene``, with the invariance check
    of the twin scene in its attributes."""
    parts = []
    for scene in scenes:
        with xr.open_dataset(scene_path(data_dir, scene), engine="netcdf4") as ds:
            parts.append(ds.load())
    atlas = xr.concat(parts, dim="scene", combine_attrs="drop_conflicts").assign_coords(scene=[s.name for s in scenes])
    atlas["scene"].attrs = ATLAS["scene"].attrs()
    atlas.attrs.update(provenance(base, "fits"))
    atlas.attrs.update(title="g2tom atlas over the groups (mu, Pi)", stage="atlas",
                       base_scenario="the scenario every scene starts from (sigma and R* kept, eta and beta "
                                     "from the scene's groups); its parameters follow")
    atlas.attrs["scene_config_hashes"] = " ".join(p.attrs["config_hash"] for p in parts)
    scene, twin = _twin(scenes)
    with xr.open_dataset(scene_path(data_dir, twin), engine="netcdf4") as twin_ds:
        error = _invariance(parts[scenes.index(scene)], twin_ds.load())
    atlas.attrs.update(invariance_pair=f"{scene.name} and {twin.name} (sigma x {TWIN_SCALE:g}, R* / {TWIN_SCALE:g}: "
                                       f"mu {scene.mu:.4g}, Pi {scene.Pi:.4g})",
                       invariance_max_ln_error=error)
    target = Path(data_dir) / "atlas" / ATLAS_FILE
    with atomic_path(target) as tmp:
        atlas.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    return target


def _line(done: int, total: int, name: str, seconds: float, scene: Scene) -> None:
    print(f"atlas: scene {name} (mu {scene.mu:.4g}, Pi {scene.Pi:.4g}) in {seconds:.1f} s [{done}/{total}]",
          file=sys.stderr)


def longest_first(scenes: list[Scene], estimates: list[SceneEstimate]) -> list[Scene]:
    """``scenes`` by their planned seconds, longest first (ties in the given order): the order the
    plan's wall time assumes (:func:`g2tom.atlas.design.wall_seconds`); a long scene started
    last would run alone at the end."""
    seconds = {e.scene.name: e.seconds for e in estimates}
    return sorted(scenes, key=lambda s: -seconds[s.name])


def run_atlas(base: Scenario, design: AtlasDesign, data_dir: str | Path,
              options: ComputeOptions = _ONE) -> Path:
    """Every scene not yet written, one per task, then ``atlas.nc``.

    Parameters
    ----------
    base
        The scenario every scene starts from (its sigma and R* are the reference lengths).
    design
        Where the scenes lie in (mu, Pi).
    data_dir
        The data directory (``atlas/`` is made under it).
    options
        ``scheduler`` or ``workers`` > 1: a dask.distributed cluster, one single-threaded scene per
        task; otherwise the scenes run one after the other in this process. A scene that runs alone
        (the one left of a resumed atlas, the invariance twin, every scene without a cluster, or
        one of the longest that :func:`g2tom.atlas.design.schedule` runs alone first because it
        would outlast the others' share) computes with ``options`` itself, on every worker.

    Raises
    ------
    ConfigError
        Before any work, if the plan or the preflight refuses a scene (naming it).
    """
    from g2tom.compute import _client

    data_dir = Path(data_dir)
    scenes = design_scenes(design)
    pending = [s for s in scenes if not _done(base, s, data_dir)]
    original, twin = _twin(scenes)
    twin_loading = scene_scenario(base, original).loading  # the same approaches in sigma, exactly
    twin_pending = not _done(twin_base(base), twin, data_dir, twin_loading)
    estimates = plan_atlas(base, design)
    refused = [e for e in estimates if e.problem and e.scene in pending]
    if refused:
        e = refused[0]
        raise ConfigError(f"atlas scene {e.scene.name} (mu {e.scene.mu:.4g}, Pi {e.scene.Pi:.4g}): {e.problem}")
    workers = 1 if options.scheduler is None and not (options.workers and options.workers > 1) else (
        options.workers or 1)
    left = [e for e in estimates if e.scene in pending]
    if pending:  # the plan's total for what is left (the whole table: `g2tom plan --atlas`)
        for line in format_atlas_plan(left, workers)[1 + len(left):]:  # the total, and the budget if over
            print(f"atlas: plan: {line}", file=sys.stderr)
    by_name = {s.name: s for s in scenes}
    # a scene that runs alone (one left, one after another, the twin, or one that would outlast the
    # others' share: `schedule`) computes on everything asked for
    alone = ComputeOptions(scheduler=options.scheduler, workers=options.workers, progress=False)
    ordered = longest_first(pending, estimates)
    first = schedule([e.seconds for e in left], workers)[0] if len(pending) > 1 else 0
    for k, scene in enumerate(ordered[:first], 1):
        _line(k, len(pending), *_run_scene(base, scene, data_dir, None, alone), scene)
    rest = [s for s in pending if s not in ordered[:first]]
    with ExitStack() as stack:
        client = _client(stack, options) if len(rest) > 1 else None
        if client is None:
            for k, scene in enumerate(rest, first + 1):
                _line(k, len(pending), *_run_scene(base, scene, data_dir, None, alone), scene)
        else:
            done = in_turn(client, functools.partial(_run_scene, base), ordered[first:], lambda s: f"atlas-{s.name}",
                           data_dir)
            for k, (name, seconds) in enumerate(done, first + 1):
                _line(k, len(pending), name, seconds, by_name[name])
    if twin_pending:  # the invariance check: equal (mu, Pi), other dimensions
        _line(1, 1, *_run_scene(twin_base(base), twin, data_dir, twin_loading, alone), twin)
    return _gather(base, scenes, data_dir)

