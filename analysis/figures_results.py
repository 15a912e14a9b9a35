"""Result figures: Barber's bounds (Fig. 3), resistance and conductance against load
(Figs. 8, 9), alpha and gamma with their surrogate (Fig. 10) and G2TOM against the
p-averaged Barber bounds (Fig. 11).

Selections follow the paper and fall back to the nearest values the scenario computed:
Figs. 8–9 at xi in {0.3, 0.5, 0.7} and lambda in {9, 19}; Fig. 11 (a) at lambda = 5 with
s = sigma and p = 0.6, (b) at lambda = 15 with s = 2 sigma and p = 0.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from g2tom.analysis.style import COLORS, LABELS, context, equals, plain_log_ticks, save, size
from g2tom.config import Scenario
from g2tom.physics import barber
from g2tom.fitting.surrogate import evaluate
from g2tom.store import read_stage

__all__ = ["write"]

FIG8_XI = (0.3, 0.5, 0.7)
FIG8_LAMBDA = (9.0, 19.0)
FIG11 = ((5.0, 1.0, 0.6), (15.0, 2.0, 0.0))  # (lambda, s/sigma, p)
FIG11_XI = (0.1, 0.3, 0.5, 0.7, 0.9)
FIG11_MAX_FORCE = 16.0
#: At most this many realizations are drawn as grey lines per curve.
MAX_GREY = 200
#: Where fig10_realizations puts a flagged cell's mark, in cell widths from its centre (the corner,
#: clear of the cell's number).
FLAG_OFFSET = (0.36, 0.33)


def nearest(available: np.ndarray, wanted: tuple[float, ...]) -> list[float]:
    """The available values nearest to each wanted one, without repeats, in order."""
    out: list[float] = []
    for w in wanted:
        value = float(available[np.argmin(np.abs(np.asarray(available) - w))])
        if value not in out:
            out.append(value)
    return out


def fig3_bounds(path: Path) -> Path:
    """Fig. 3: clean and oxide-extended bounds (Eqs. 8, 9) and their geometric mean."""
    force = np.geomspace(1e-2, 1e2, 200)
    fig, ax = plt.subplots(figsize=size(1, 3.6), layout="constrained")
    for xi, color in zip((0.0, 0.3, 0.5, 0.7), ["k", *COLORS[1:]]):
        upper, lower = barber.oxide_bounds(force, xi)
        label = "clean" if xi == 0 else equals("xi", xi)
        ax.plot(force, upper, color=color, label=f"{label}: upper")
        ax.plot(force, lower, color=color, ls="--", label=f"{label}: lower")
        ax.plot(force, barber.p_average(force, xi, 0.0), color=color, ls=":", lw=1)
    ax.plot([], [], "k:", lw=1, label=r"geometric mean $\langle\kappa'\rangle_{p=0}$")
    ax.set(xscale="log", yscale="log", xlabel=LABELS["force_normalized_s"],
           ylabel=LABELS["conductance_normalized_s"], title="Barber's bounds with oxide (Eqs. 8-10)")
    fig.legend(loc="outside lower center", ncols=2)
    ax.grid(True, which="major", alpha=0.3)
    return save(fig, path)


def _grey(ax: plt.Axes, x: np.ndarray, curves: np.ndarray) -> None:
    """Each realization (rows of ``curves``) as a faint grey line; non-finite points dropped."""
    segments = []
    for row in curves[:MAX_GREY]:
        ok = np.isfinite(row) & (row > 0)
        if ok.sum() > 1:
            segments.append(np.column_stack([x[ok], row[ok]]))
    ax.add_collection(LineCollection(segments, colors="0.6", alpha=0.12, lw=0.5, zorder=1))
    if segments:  # a collection does not enter the autoscaled limits by itself: no clipped lines
        ax.update_datalim(np.concatenate(segments))
        ax.autoscale_view()


def _load_panel(ax: plt.Axes, cube: xr.Dataset, fits: xr.Dataset, lam: float, xis: list[float], normalized: bool) -> None:
    """R(F) (or kappa'(F')) at one lambda for several xi: grey lines, band, markers, fit."""
    scale = float(fits["resistance_scale"])
    x = fits["force_normalized"].values if normalized else fits["force"].values
    fitted = fits["fitted"].values.astype(bool)
    dense = np.geomspace(x[fitted].min(), x[fitted].max(), 50)
    f_dense = dense if normalized else dense * fits["force_normalized"].values[fitted][0] / x[fitted][0]

    def show(r: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return scale / r if normalized else r

    for xi, color in zip(xis, COLORS):
        cell = {"xi": xi, "lambda": lam}
        _grey(ax, x, show(cube["resistance"].sel(cell).transpose("realization", "delta").values))
        q = fits["resistance_quantile"].sel(cell)
        lo, hi = show(q.sel(quantile=0.16).values), show(q.sel(quantile=0.84).values)
        top = np.nanmax(np.where(np.isfinite(np.r_[lo, hi]), np.r_[lo, hi], np.nan)) * 10
        ax.fill_between(x, np.nan_to_num(lo, posinf=top), np.nan_to_num(hi, posinf=top), color=color, alpha=0.25, lw=0, zorder=2)
        center = fits[fits.attrs["reduction"]].sel(cell).values  # the reduction that was fitted
        ax.plot(x, show(center), "o", color=color, zorder=3, label=equals("xi", xi))
        alpha, gamma = float(fits["alpha"].sel(cell)), float(fits["gamma"].sel(cell))
        r_fit = alpha * scale * f_dense**-gamma
        ax.plot(dense, show(r_fit), color=color, lw=1.2, zorder=4)
    ax.plot(x, show(fits["resistance_clean"].values), "k-", lw=1, label="clean")
    ax.set(xscale="log", yscale="log", title=equals("lambda", lam))
    ax.set_xlim(x[x > 0].min(), x.max())
    ax.grid(True, which="major", alpha=0.3)


def fig_load(path: Path, cube: xr.Dataset, fits: xr.Dataset, normalized: bool) -> Path:
    """Fig. 8 (R against F, ohm and N) or Fig. 9 (kappa' = 1/R' against F')."""
    lams = nearest(fits["lambda"].values, FIG8_LAMBDA)
    xis = nearest(fits["xi"].values, FIG8_XI)
    fig, axes = plt.subplots(1, len(lams), figsize=size(2, 3.2), squeeze=False, sharey=True, layout="constrained")
    for ax, lam in zip(axes[0], lams):
        _load_panel(ax, cube, fits, lam, xis, normalized)
        ax.set_xlabel(LABELS["force_normalized" if normalized else "force"])
    axes[0, 0].set_ylabel(LABELS["conductance_normalized" if normalized else "resistance"])
    handles, labels = axes[0, 0].get_legend_handles_labels()
    center = fits.attrs["reduction"].replace("_", " ")
    keys = [(Line2D([], [], color="C0", lw=1.2), f"lines in colour: power-law fit of the {center}"),
            (Patch(color="0.5", alpha=0.35, lw=0), "16-84 % band over realizations"),
            (Line2D([], [], color="0.6", lw=0.8), "single realizations")]
    fig.legend(handles + [h for h, _ in keys], labels + [t for _, t in keys],
               loc="outside lower center", ncols=3)
    return save(fig, path)


def fig10_alpha_gamma(path: Path, fits: xr.Dataset, surrogate: xr.Dataset) -> Path:
    """Fig. 10: fitted alpha (log axis: it grows by decades with xi), gamma against xi per lambda,
    the surrogate, and its error map."""
    lams = fits["lambda"].values
    xi_dense = np.linspace(float(fits.xi.min()), float(fits.xi.max()), 100)
    colors = plt.cm.viridis(np.linspace(0, 0.85, lams.size))
    fig, axes = plt.subplots(2, 2, figsize=size(2, 5.4), layout="constrained")
    for col, name in enumerate(("alpha", "gamma")):
        ax = axes[0, col]
        for lam, color in zip(lams, colors):
            value = fits[name].sel({"lambda": lam})
            ci = fits[f"{name}_ci"].sel({"lambda": lam})
            err = np.abs(np.vstack([value - ci.sel(bound="lower"), ci.sel(bound="upper") - value]))
            ax.errorbar(fits.xi, value, yerr=err, fmt="o", color=color, capsize=2, label=f"{lam:g}")
            coef = (surrogate[f"{name}_coef_w"].values, surrogate[f"{name}_coef_z"].values)
            transform = str(surrogate.attrs.get(f"{name}_transform", "identity"))
            ax.plot(xi_dense, evaluate(*coef, lam, xi_dense, transform), color=color)
        if name == "alpha":
            ax.set_yscale("log")
            plain_log_ticks(ax.yaxis)
        ax.set(xlabel=LABELS["xi"], ylabel=LABELS[name], title="fits (markers, 95 % CI), surrogate (lines)")
        ax.grid(True, which="major", alpha=0.3)
        error = 100 * surrogate[f"{name}_relative_error"].transpose("lambda", "xi")
        ax = axes[1, col]
        limit = max(float(np.abs(error).max()), 1e-6)
        mesh = ax.imshow(error.values, origin="lower", cmap="RdBu_r", vmin=-limit, vmax=limit, aspect="auto")
        _cell_ticks(ax, fits)
        ax.set_title(f"{LABELS[name]}: surrogate error")
        fig.colorbar(mesh, ax=ax, label=LABELS["relative_error"])
    fig.legend(*axes[0, 0].get_legend_handles_labels(), title=LABELS["lambda"], loc="outside right upper")
    return save(fig, path)


def _cell_ticks(ax: plt.Axes, fits: xr.Dataset) -> None:
    """Ticks and labels of a (lambda, xi) heat map drawn with imshow (one cell per index)."""
    ax.set_xticks(range(fits.xi.size), [f"{v:g}" for v in fits.xi.values])
    ax.set_yticks(range(fits["lambda"].size), [f"{v:g}" for v in fits["lambda"].values])
    ax.set(xlabel=LABELS["xi"], ylabel=LABELS["lambda"])


def fig10_realizations(path: Path, fits: xr.Dataset) -> Path:
    """Beside Fig. 10: heat maps of the realizations used and of alpha's reached half-width.

    Each cell shows its number at its centre; a flagged cell (the fit missed its precision) gets
    a mark in its upper right corner (:data:`FLAG_OFFSET`), clear of the number.
    """
    fig, axes = plt.subplots(1, 2, figsize=size(2, 2.8), layout="constrained")
    panels = (
        ("n_realizations", LABELS["realizations"], "viridis", 1.0),
        ("alpha_half_width", LABELS["half_width"], "magma", 100.0),
    )
    flagged = fits["flagged"].transpose("lambda", "xi").values.astype(bool)
    lam_index, xi_index = np.nonzero(flagged)
    for ax, (name, title, cmap, factor) in zip(axes, panels):
        values = factor * fits[name].transpose("lambda", "xi").values
        mesh = ax.imshow(values, origin="lower", cmap=cmap, aspect="auto")
        for (a, z), value in np.ndenumerate(values):
            ax.text(z, a, f"{value:.0f}" if factor == 1.0 else f"{value:.1f}", ha="center", va="center",
                    color="w" if value < np.nanmean(values) else "k")
        ax.plot(xi_index + FLAG_OFFSET[0], lam_index + FLAG_OFFSET[1], "x", color="tab:red", mew=1.2,
                ls="none", label="flagged")
        _cell_ticks(ax, fits)
        ax.set_title(title)
        fig.colorbar(mesh, ax=ax)
    return save(fig, path)


def fig11_barber(path: Path, fits: xr.Dataset) -> Path:
    """Fig. 11: G2TOM geometric-mean conductance against the p-average of Eq. 10."""
    fig, axes = plt.subplots(1, 2, figsize=size(2, 3.2), sharey=True, layout="constrained")
    force_n = fits["force_normalized"].values
    show = (force_n > 0) & (force_n <= FIG11_MAX_FORCE)
    dense = np.geomspace(force_n[show].min(), force_n[show].max(), 100)
    xis = nearest(fits["xi"].values, FIG11_XI)
    for ax, (lam_wanted, s_ratio, p), letter in zip(axes, FIG11, "ab"):
        lam = nearest(fits["lambda"].values, (lam_wanted,))[0]
        for xi, color in zip(xis, COLORS):
            kappa = 1.0 / fits["geometric_mean_normalized"].sel(xi=xi, **{"lambda": lam}).values
            ax.plot(force_n[show], kappa[show], "o", color=color, label=f"G2TOM, {equals('xi', xi)}")
            ax.plot(dense, barber.p_average_sigma(dense, xi, p, s_ratio), "--", color=color)
        clean = 1.0 / fits["resistance_clean_normalized"].values
        ax.plot(force_n[show], clean[show], "ks", label="G2TOM, clean")
        ax.plot(dense, barber.p_average_sigma(dense, 0.0, p, s_ratio), "k--", label="Barber, Eq. 10 (dashed)")
        ax.set(xscale="log", yscale="log", xlabel=LABELS["force_normalized"],
               title=f"({letter}) {equals('lambda', lam)}, $s = {'' if s_ratio == 1 else f'{s_ratio:g}'}\\sigma$, "
                     f"$p = {p:g}$")
        plain_log_ticks(ax.xaxis, subs=(1.0, 2.0, 5.0))
        plain_log_ticks(ax.yaxis, subs=(1.0, 2.0, 5.0))
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel(LABELS["conductance_short"])
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=3)
    return save(fig, path)


def write(scenario: Scenario, data_dir: Path, out_dir: Path) -> list[Path]:
    """Write Figs. 3, 8, 9, 10 (with its realizations map) and 11 under ``out_dir``, in that order."""
    cube = read_stage(data_dir, "cube", scenario, select=lambda ds: ds[["resistance"]])  # the grey lines' realizations
    fits = read_stage(data_dir, "fits", scenario)
    surrogate = read_stage(data_dir, "surrogate", scenario)
    out_dir = Path(out_dir)
    with context():
        return [
            fig3_bounds(out_dir / "fig3_bounds.png"),
            fig_load(out_dir / "fig8_resistance.png", cube, fits, normalized=False),
            fig_load(out_dir / "fig9_conductance.png", cube, fits, normalized=True),
            fig10_alpha_gamma(out_dir / "fig10_alpha_gamma.png", fits, surrogate),
            fig10_realizations(out_dir / "fig10_realizations.png", fits),
            fig11_barber(out_dir / "fig11_barber.png", fits),
        ]
