"""Greenwood's closed form against the exact point-interaction model, and partially conductive oxide.

Reads the model comparison of ``make compare``: the stages run twice on one modest ensemble,
under ``<data_dir>/compare/greenwood`` and ``<data_dir>/compare/point`` (``cube.model`` set
accordingly; identical oxide masks). Writes, when that comparison exists (nothing otherwise):

* ``point_alpha_gamma``: alpha_point / alpha_greenwood and gamma_point - gamma_greenwood
  against lambda for every xi;
* ``point_film``: the geometric-mean resistance over realizations at the heaviest load step
  against the film's specific resistance r_f, for a few (xi, lambda), with both models
  (the exact solve and Greenwood's form generalized to films), between the clean and the
  insulating limits.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from g2tom.analysis.style import LABELS, context, equals, save, size
from g2tom.config import Scenario
from g2tom.physics import point_model
from g2tom.physics.spot_geometry import SpotGeometry

__all__ = ["COMPARE", "MODELS", "load_comparison", "film_sweep", "write"]

COMPARE = "compare"
MODELS = ("greenwood", "point")
#: (xi, lambda) of the film sweep (nearest computed values) and its realizations.
FILM_CASES = ((0.3, 5.0), (0.7, 5.0), (0.7, 19.0))
FILM_REALIZATIONS = 8
#: Film specific resistances of the sweep, in ohm m^2.
FILM_VALUES = np.logspace(-15, -6, 19)


def load_comparison(data_dir: Path) -> dict[str, xr.Dataset] | None:
    """``fits.nc`` of both models under ``<data_dir>/compare``, or None if either is missing.

    Raises
    ------
    ValueError
        If the two runs do not share one oxide ensemble or a file holds the wrong model.
    """
    paths = {m: Path(data_dir) / COMPARE / m / "fits.nc" for m in MODELS}
    if not all(p.is_file() for p in paths.values()):
        return None
    out = {}
    for model, path in paths.items():
        with xr.open_dataset(path, engine="netcdf4") as ds:
            out[model] = ds.load()
        if out[model].attrs.get("cube.model") != model:
            raise ValueError(f"{path} holds cube.model = {out[model].attrs.get('cube.model')!r}, not {model!r}")
    keys = [k for k in out["point"].attrs if k.startswith(("oxide.", "contact.", "loading.", "roughness."))]
    differ = [k for k in keys if str(out["point"].attrs[k]) != str(out["greenwood"].attrs.get(k))]
    if differ:
        raise ValueError(f"the model comparison's two runs differ in {', '.join(differ)}")
    return out


def _nearest(values: np.ndarray, wanted: float) -> int:
    return int(np.argmin(np.abs(np.asarray(values) - wanted)))


def film_sweep(data_dir: Path, films: np.ndarray | None = None) -> dict[str, np.ndarray] | None:
    """Geometric-mean R over realizations at the heaviest load against r_f, both models.

    Parameters
    ----------
    data_dir
        The main data directory (the comparison lives under ``compare/point``).
    films
        Film specific resistances, in ohm m^2; :data:`FILM_VALUES` by default.

    Returns
    -------
    dict or None
        ``film`` (ohm m^2), ``cases`` ((xi, lambda) pairs), ``point`` and ``greenwood``
        (case, film) and their ``*_clean`` (case,) and ``*_insulating`` (case,) limits, in
        ohm; None when the comparison's contact or oxide file is missing.
    """
    base = Path(data_dir) / COMPARE / "point"
    if not ((base / "contact.nc").is_file() and (base / "oxide.nc").is_file()):
        return None
    with xr.open_dataset(base / "contact.nc", engine="netcdf4") as contact, \
            xr.open_dataset(base / "oxide.nc", engine="netcdf4") as oxide:
        radius = contact["spot_radius"].transpose("delta", "y", "x").values[-1:].astype(np.float64)
        x = contact["x"].values
        rho = float(contact.attrs["material.rho"])
        psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values[:, :FILM_REALIZATIONS]
        thr = oxide["threshold"].transpose("xi", "lambda", "realization").values[:, :, :FILM_REALIZATIONS]
        cases = [(float(oxide["xi"].values[_nearest(oxide["xi"].values, xi)]),
                  float(oxide["lambda"].values[_nearest(oxide["lambda"].values, lam)])) for xi, lam in FILM_CASES]
        masks = np.concatenate([
            psi[_nearest(oxide["lambda"].values, lam)] < thr[_nearest(oxide["xi"].values, xi),
                                                              _nearest(oxide["lambda"].values, lam)][:, None, None]
            for xi, lam in cases])
    pitch = float(x[1] - x[0])
    whole = SpotGeometry.whole_window(radius, radius, pitch)

    def gmean(r: np.ndarray) -> np.ndarray:
        return np.exp(np.log(r.reshape(len(cases), -1)).mean(axis=1))

    films = FILM_VALUES if films is None else np.asarray(films, float)
    out: dict[str, np.ndarray] = {"film": films, "cases": np.asarray(cases)}
    for name, func in (("point", point_model.resistance), ("greenwood", point_model.greenwood_resistance)):
        rows = [gmean(func(masks, whole, rho, film_resistance=f).resistance) for f in films]
        out[name] = np.stack(rows, axis=1)
        out[f"{name}_clean"] = gmean(func(np.ones_like(masks), whole, rho).resistance)
        insulating = func(masks, whole, rho).resistance
        out[f"{name}_insulating"] = gmean(insulating) if np.all(np.isfinite(insulating)) else np.full(len(cases), np.inf)
    return out


def _alpha_gamma(fits: dict[str, xr.Dataset], path: Path) -> Path:
    fig, axes = plt.subplots(1, 2, figsize=size(2, 2.8), layout="constrained")
    g, p = fits["greenwood"], fits["point"]
    ratio = (p["alpha"] / g["alpha"]).transpose("xi", "lambda")
    shift = (p["gamma"] - g["gamma"]).transpose("xi", "lambda")
    lam = g["lambda"].values
    for i, xi in enumerate(g["xi"].values):
        color = plt.cm.viridis(0.85 * i / max(1, g["xi"].size - 1))
        axes[0].plot(lam, ratio.values[i], "o-", color=color, label=equals("xi", xi))
        axes[1].plot(lam, shift.values[i], "o-", color=color)
    clean_ratio = float(p["alpha_clean"] / g["alpha_clean"])
    clean_shift = float(p["gamma_clean"] - g["gamma_clean"])
    axes[0].axhline(clean_ratio, color="k", ls="--", label="clean")
    axes[1].axhline(clean_shift, color="k", ls="--")
    axes[0].set(xlabel=LABELS["lambda"], ylabel=LABELS["alpha_ratio"])
    axes[1].set(xlabel=LABELS["lambda"], ylabel=LABELS["gamma_shift"])
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside right center")
    return save(fig, path)


def _film(sweep: dict[str, np.ndarray], path: Path) -> Path:
    fig, ax = plt.subplots(figsize=size(1, 3.8), layout="constrained")
    for i, (xi, lam) in enumerate(sweep["cases"]):
        color = f"C{i}"
        ax.loglog(sweep["film"], sweep["point"][i], "o-", color=color,
                  label=f"point, {equals('xi', xi)}, {equals('lambda', lam)}")
        ax.loglog(sweep["film"], sweep["greenwood"][i], "x:", color=color, label="Greenwood (films)")
        ax.axhline(sweep["point_clean"][i], color=color, lw=0.6, ls="--")
        if np.isfinite(sweep["point_insulating"][i]):
            ax.axhline(sweep["point_insulating"][i], color=color, lw=0.6, ls="-.")
    ax.set(xlabel=LABELS["film"], ylabel=LABELS["resistance_heaviest"], title="clean (--) to insulating (-.) oxide")
    fig.legend(loc="outside lower center")
    return save(fig, path)


def write(scenario: Scenario, data_dir: Path, out_dir: Path, films: np.ndarray | None = None) -> list[Path]:
    """Both figures when ``make compare`` has run (``films`` as in :func:`film_sweep`); nothing otherwise."""
    fits = load_comparison(data_dir)
    if fits is None:
        return []
    sweep = film_sweep(data_dir, films)
    with context():
        written = [_alpha_gamma(fits, out_dir / "point_alpha_gamma.png")]
        if sweep is not None:
            written.append(_film(sweep, out_dir / "point_film.png"))
    return written
