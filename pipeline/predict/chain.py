"""The measured-surface chain, measured: a surface's height map -> ``g2tom roughness`` -> ``g2tom
predict``, against the full elastic field of that very surface.

The validation's random-process surface (``g2tom validate --surface random_process``, a Gaussian
self-affine surface whose full-field contact and resistance :mod:`g2tom.reference` solves) is
what a profilometer would measure. For every realization of the validation set:

1. its heights over the set's window (:func:`g2tom.reference.scene.rough_sphere` less the sphere,
   :func:`g2tom.reference.surfaces.sphere`) are written as a height map (``.npy``, m) of
   :data:`MAP_PIXELS` pixels a side;
2. the map is measured as ``g2tom roughness`` does (:func:`g2tom.heightmap.measure`: summit
   sigma, eta, beta from its spectral moments below 4 pixels);
3. the resistance is predicted as ``g2tom predict --roughness MAP`` does
   (:func:`g2tom.predict.domain.with_measured_roughness` on ``paper`` with the set's sphere and
   material, the surrogate :func:`g2tom.predict.answer.choose_surrogate` picks: the atlas's) at the
   forces the full field was solved at, clean (the atlas surrogate's node xi = 0) and for every
   oxide case (xi, lambda) of the set; the same with the set's own sigma, eta, beta (the closed form
   of its spectrum: the chain without the measurement) beside it;
4. each is divided by the full field's resistance of that realization (``validate.nc``).

``chain.nc`` (beside ``validate.nc``) holds the ratios per (case, realization, load) and their
geometric means and standard errors of ln over the realizations per load; the report prints them
(``analysis/report_chain.py``). Run ``python -m g2tom.predict.chain --data-dir DATA`` after
``g2tom validate --surface random_process`` (``--quick`` too).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.config import ConfigError, Scenario
from g2tom.before_work import load_scenario
from g2tom.store import atomic_path, git_commit
from g2tom.variables import namespace

__all__ = ["CHAIN_FILE", "MAP_PIXELS", "chain_dataset", "run_chain", "main"]

CHAIN_FILE = "chain.nc"
#: Pixels along a side of the height map written for each realization (over the set's window: 2.2
#: um on the quick set, 4.4 um on the default one, 16 and 8 pixels per shortest wavelength).
MAP_PIXELS = 1024


def _validation_set(ds: xr.Dataset):
    """The validation set a ``validate.nc`` was made of (its scalar attributes, realizations, cases)."""
    from g2tom.reference import scene

    fields = {f.name for f in dataclasses.fields(scene.ValidationSet)}
    values = {k.removeprefix("scene_"): (v.item() if hasattr(v, "item") else v) for k, v in ds.attrs.items()
              if k.startswith("scene_") and k.removeprefix("scene_") in fields}
    deltas = tuple(float(d) for d in ds["delta_g2tom"].values / values["sigma"])
    return dataclasses.replace(scene.ValidationSet(), **values, deltas=deltas,
                               realizations=tuple(int(r) for r in ds["realization"].values),
                               xi=tuple(float(x) for x in ds["xi"].values),
                               lambdas=tuple(float(x) for x in ds["lambda"].values))


def _height_map(vset, realization: int, folder: Path) -> tuple[Path, float]:
    """The realization's rough surface (no sphere) as a ``.npy`` height map (m) and its pixel (m)."""
    from g2tom.reference import scene, surfaces

    pixel = vset.side / MAP_PIXELS
    heights = scene.rough_sphere(vset, realization, MAP_PIXELS) - surfaces.sphere(MAP_PIXELS, pixel, vset.radius)
    path = folder / f"random_process_{realization}.npy"
    np.save(path, heights)
    return path, pixel


def _surface(vset) -> Scenario:
    """``paper`` with the set's sphere, material and (closed-form) summit parameters."""
    return load_scenario("paper", {"indenter.radius": vset.radius, "material.E": vset.E, "material.nu": vset.nu,
                                   "material.rho": vset.rho, "roughness.sigma": vset.sigma,
                                   "roughness.eta": vset.eta, "roughness.beta": vset.beta})


def _predicted(surrogate, scenario: Scenario, force: np.ndarray, xi: np.ndarray, lam: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """R (ohm) clean and per oxide case (xi, lambda, load), and whether each load lies in the domain."""
    from g2tom.predict.answer import predict_with
    from g2tom.predict.atlas import AtlasSurrogate
    from g2tom.scene import scene_groups

    force_n = force / scenario.force_scale
    inside = np.ones(force.size, bool)
    if isinstance(surrogate, AtlasSurrogate):
        lo, hi = surrogate.domain["force_normalized"]
        inside = (force_n >= lo * (1 - 1e-12)) & (force_n <= hi * (1 + 1e-12))
        g = scene_groups(scenario)
        for name, value in (("mu", g.mu), ("Pi", g.Pi)):
            lo, hi = surrogate.domain[name]
            inside &= lo * (1 - 1e-12) <= value <= hi * (1 + 1e-12)
    oxidized = np.full((xi.size, lam.size, force.size), np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # outside the domain: answered, flagged in `inside`
        for i, x in enumerate(xi):
            for j, l in enumerate(lam):
                oxidized[i, j] = predict_with(surrogate, scenario, force, x, l, extrapolate=True)["resistance"].values
        clean = np.full(force.size, np.nan)
        if isinstance(surrogate, AtlasSurrogate) and surrogate.band is not None:  # the clean node xi = 0
            g = scene_groups(scenario)
            n = force.size
            clean = np.exp(surrogate.log_resistance(np.zeros(n), np.ones(n), np.full(n, g.mu), np.full(n, g.Pi),
                                                    force_n)) * scenario.resistance_scale
    return clean, oxidized, inside


def chain_dataset(validate_nc: str | Path, data_dir: str | Path = "data", surrogate: str | Path | None = None,
                  work: str | Path | None = None) -> xr.Dataset:
    """The chain on every realization of a random-process ``validate.nc`` (see the module).

    Parameters
    ----------
    validate_nc
        ``validate.nc`` of ``g2tom validate --surface random_process``.
    data_dir
        The data directory whose atlas surrogate answers (else the shipped one).
    surrogate
        A surrogate file to answer with instead.
    work
        Where the height maps are written (default: a temporary directory, removed after).

    Raises
    ------
    ConfigError
        If ``validate.nc`` is missing or not of the random-process surface.
    """
    from g2tom.heightmap import measure
    from g2tom.predict.answer import choose_surrogate
    from g2tom.predict.domain import with_measured_roughness
    from g2tom.scene import scene_groups

    validate_nc = Path(validate_nc)
    if not validate_nc.is_file():
        raise ConfigError(f"validate.nc {str(validate_nc)!r} does not exist: run `g2tom validate --surface "
                          "random_process` (or with --quick) first")
    with xr.open_dataset(validate_nc, engine="netcdf4") as ds:
        ds = ds.load()
    if ds.attrs.get("scene_surface") != "random_process":
        raise ConfigError(f"validate.nc {str(validate_nc)!r} is of the {ds.attrs.get('scene_surface')!r} surface: the "
                          "chain needs the random_process one")
    vset = _validation_set(ds)
    force = ds["force"].values.astype(float)
    xi, lam = ds["xi"].values.astype(float), ds["lambda"].values.astype(float)
    known = _surface(vset)
    answering = choose_surrogate(known, data_dir, surrogate)
    n_r, n_l = len(vset.realizations), force.size
    out = {k: np.full((n_r, n_l), np.nan) for k in ("clean", "clean_known", "inside", "force_normalized")}
    out.update({k: np.full((xi.size, lam.size, n_r, n_l), np.nan) for k in ("oxidized", "oxidized_known")})
    measured = {k: np.full(n_r, np.nan) for k in ("sigma", "eta", "beta", "rms_height", "mu", "Pi")}
    known_clean, known_oxidized, _ = _predicted(answering, known, force, xi, lam)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(work) if work is not None else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for k, realization in enumerate(vset.realizations):
            path, pixel = _height_map(vset, realization, folder)
            m = measure(path, pixel)
            scenario = with_measured_roughness(known, path, pixel)
            g = scene_groups(scenario)
            for name, value in (("sigma", m["sigma"]), ("eta", m["eta"]), ("beta", m["beta"]),
                                ("rms_height", m["rms_height"]), ("mu", g.mu), ("Pi", g.Pi)):
                measured[name][k] = value
            clean, oxidized, inside = _predicted(answering, scenario, force, xi, lam)
            out["clean"][k], out["oxidized"][:, :, k], out["inside"][k] = clean, oxidized, inside
            out["force_normalized"][k] = force / scenario.force_scale
            out["clean_known"][k], out["oxidized_known"][:, :, k] = known_clean, known_oxidized
    ref_clean = ds["resistance_reference_clean"].transpose("realization", "load").values
    ref = ds["resistance_reference"].transpose("xi", "lambda", "realization", "load").values
    with np.errstate(invalid="ignore", divide="ignore"):
        ratios = {"ratio_clean": out["clean"] / ref_clean, "ratio": out["oxidized"] / ref,
                  "ratio_clean_known": out["clean_known"] / ref_clean, "ratio_known": out["oxidized_known"] / ref}
    return _dataset(ds, vset, measured, out, ratios, answering)


def _log_mean(ratio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Geometric mean over the realization axis (-2) and the standard error of its ln (NaN below 2)."""
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # one realization: no spread, NaN
        ln = np.where(np.isfinite(np.log(ratio)), np.log(ratio), np.nan)
        n = np.sum(np.isfinite(ln), axis=-2)
        mean = np.nanmean(ln, axis=-2) if ln.size else ln
        se = np.where(n >= 2, np.nanstd(ln, axis=-2, ddof=1) / np.sqrt(np.maximum(n, 1)), np.nan) if n.size else n
    return np.exp(mean), se


def _dataset(ds: xr.Dataset, vset, measured: dict, out: dict, ratios: dict, answering) -> xr.Dataset:
    declared = namespace("chain")

    def var(name: str, data: np.ndarray) -> tuple:
        return declared[name].dims, data, declared[name].attrs()

    data = {
        **{f"measured_{k}": var(f"measured_{k}", v) for k, v in measured.items()},
        "force_normalized_measured": var("force_normalized_measured", out["force_normalized"]),
        "inside_domain": var("inside_domain", out["inside"].astype(np.int8)),
        "resistance_chain_clean": var("resistance_chain_clean", out["clean"]),
        "resistance_chain": var("resistance_chain", out["oxidized"]),
        **{name: var(name, ratios[name]) for name in ("ratio_clean", "ratio", "ratio_clean_known", "ratio_known")},
    }
    for name in ("ratio_clean", "ratio", "ratio_clean_known", "ratio_known"):
        gm, se = _log_mean(ratios[name])
        data[f"{name}_mean"] = var(f"{name}_mean", gm)
        data[f"{name}_standard_error"] = var(f"{name}_standard_error", se)
    coords = {k: ds[k] for k in ("realization", "load", "xi", "lambda")}
    coords.update(force=ds["force"], force_normalized=ds["force_normalized"])
    chain = xr.Dataset(data, coords=coords)
    chain.attrs.update({
        "title": "g2tom's measured-surface chain against the full field: height map -> roughness -> predict",
        "answered_by": answering.describe() if hasattr(answering, "describe") else str(answering),
        "map_pixels": MAP_PIXELS, "map_pixel": vset.side / MAP_PIXELS, "set_sigma": vset.sigma, "set_eta": vset.eta,
        "set_beta": vset.beta, "set_radius": vset.radius, "g2tom_commit": git_commit() or "unknown",
        "reference": "validate.nc of the random_process surface (g2tom.reference)",
    })
    return chain


def run_chain(data_dir: str | Path, surrogate: str | Path | None = None) -> Path:
    """``chain.nc`` beside ``<data_dir>/validate_random_process/validate.nc``, written atomically."""
    from g2tom.reference.validate import output_folder

    folder = output_folder(Path(data_dir), "random_process")
    chain = chain_dataset(folder / "validate.nc", data_dir, surrogate)
    target = folder / CHAIN_FILE
    with atomic_path(target) as tmp:
        chain.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    return target


def main(argv: list[str] | None = None) -> int:
    """``python -m g2tom.predict.chain [--data-dir DATA] [--surrogate FILE]``: exit 0, or 2 with one
    ``g2tom: error:`` line."""
    parser = argparse.ArgumentParser(prog="python -m g2tom.predict.chain", description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default="data", help="data directory (its validate_random_process/validate.nc)")
    parser.add_argument("--surrogate", default=None, help="a surrogate file to answer with (default: the atlas's)")
    args = parser.parse_args(argv)
    try:
        target = run_chain(args.data_dir, args.surrogate)
    except ConfigError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 2
    print(f"chain: wrote {target}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
