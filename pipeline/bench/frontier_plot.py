"""The frontier's figures: ``frontier_contact.png``, ``frontier_cube.png``, ``frontier_ensemble.png``
and, with an adaptive cube's prefix curve, ``frontier_prefix.png``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.bench import frontier_sweeps as sweeps

__all__ = ["plot"]


def plot(frontier: xr.Dataset, out_dir: str | Path) -> list[Path]:
    """``frontier_contact.png``, ``frontier_cube.png``, ``frontier_ensemble.png`` under ``out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator

    def plain_time_axis(ax: Any) -> None:
        """Time ticks at 1, 2, 5 x 10^k with plain labels, none on the minor ticks."""
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())

    def error_panel(ax: Any, xlabel: str, err: str) -> None:
        """An error-against-time panel's axes: plain time ticks, labels, the major grid."""
        plain_time_axis(ax)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"max relative {err.replace('_error', '')} error")
        ax.grid(True, which="major", alpha=0.3)

    def save(fig: Any, title: str, name: str) -> None:
        """Title ``fig``, write it as ``out_dir/name`` and close it."""
        fig.suptitle(title)
        paths.append(out_dir / name)
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    floor = 1e-16

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    solver = frontier["contact_solver"].values
    for ax, err in zip(axes, ("force_error", "area_error")):
        for tol in sweeps.TOLERANCES:
            sel = (solver == "newton") & np.isclose(frontier["contact_tolerance"].values, tol)
            ax.loglog(frontier["contact_seconds"].values[sel], np.maximum(frontier[f"contact_{err}"].values[sel], floor),
                      "o-", label=f"Newton, tol {tol:g}")
            for x, y, n in zip(frontier["contact_seconds"].values[sel], frontier[f"contact_{err}"].values[sel],
                               frontier["contact_n_radial"].values[sel]):
                if tol == sweeps.TOLERANCES[-1]:
                    ax.annotate(str(n), (x, max(y, floor)), fontsize=7, xytext=(3, 3), textcoords="offset points")
        fp = solver == "fixed_point"
        ax.loglog(frontier["contact_seconds"].values[fp], np.maximum(frontier[f"contact_{err}"].values[fp], floor),
                  "s", color="k", label="relaxed fixed point (20 uniform; default grid)")
        error_panel(ax, "solve time, s", err)
    axes[0].legend(fontsize=7)
    save(fig, "Contact: radial nodes (labels) and tolerance against error and time", "frontier_contact.png")

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), constrained_layout=True)
    for ax, err in zip(axes, ("resistance_error", "alpha_error", "gamma_error")):
        for method in sweeps.METHODS:
            for precision, marker in (("float64", "o-"), ("float32", "x")):
                sel = (frontier["cube_method"].values == method) & (frontier["cube_precision"].values == precision)
                if sel.any():
                    ax.loglog(frontier["cube_seconds"].values[sel], np.maximum(frontier[f"cube_{err}"].values[sel], floor),
                              marker, label=f"{method} {precision}")
        error_panel(ax, "cube time, s", err)
    axes[0].legend(fontsize=7)
    save(fig, "Cube: algorithm, crop tolerance (0, 1e-6, 1e-4, 1e-2 along each line) and precision", "frontier_cube.png")

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    n = frontier["n_realizations"].values
    for ax, name in zip(axes, ("alpha", "gamma")):
        width = frontier[f"{name}_halfwidth"]
        for xi in width["xi"].values:
            for lam in width["lambda"].values:
                ax.loglog(n, width.sel(xi=xi, **{"lambda": lam}).values, "-", alpha=0.6, label=f"xi {xi:g}, lambda {lam:g}")
        ax.loglog(n, width.max(("xi", "lambda")).values[0] * np.sqrt(n[0] / n), "k--", label="n^-1/2")
        ax.set_xlabel("realizations")
        ax.set_ylabel(f"relative half-width of the {name} interval")
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xticks(n, [str(int(v)) for v in n])
        ax.xaxis.set_minor_locator(NullLocator())
        top = ax.secondary_xaxis("top", functions=(lambda x: x, lambda x: x))
        top.set_xticks(n, [f"{t:.2g} s" for t in frontier["ensemble_seconds"].values], fontsize=7)
        top.xaxis.set_minor_locator(NullLocator())
    axes[1].legend(fontsize=6, ncol=2)
    save(fig, "Ensemble: interval width against realizations (top: time)", "frontier_ensemble.png")

    if "prefix_n" in frontier:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
        lambdas = frontier["cube_lambda"].values
        colors = plt.cm.viridis(np.linspace(0, 1, lambdas.size))
        per_realization = float(frontier.attrs["prefix_cube_seconds"]) / float(frontier["prefix_count"].sum())
        for ax, name in zip(axes, ("alpha", "gamma")):
            width = frontier[f"prefix_{name}_halfwidth"].transpose("cube_xi", "cube_lambda", "prefix_step").values
            n = frontier["prefix_n"].transpose("cube_xi", "cube_lambda", "prefix_step").values
            for j, lam in enumerate(lambdas):
                for i in range(n.shape[0]):
                    ax.loglog(n[i, j], width[i, j], "-", color=colors[j], lw=0.8, alpha=0.7,
                              label=f"lambda {lam:g}" if i == 0 else None)
                ax.loglog(n[:, j, -1], width[:, j, -1], "o", color=colors[j], ms=3)
            if name == "alpha" and "prefix_rule_target" in frontier.attrs:
                ax.axhline(frontier.attrs["prefix_rule_target"], color="k", ls="--", lw=0.8,
                           label="the rule's stopping target")
            ax.set_xlabel("realizations of the cell (dots: the adaptive ensemble's count)")
            ax.set_ylabel(f"fast-rule {'relative' if name == 'alpha' else 'absolute'} half-width of {name}")
            ax.grid(True, which="major", alpha=0.3)
            top = ax.secondary_xaxis("top", functions=(lambda x: x * per_realization, lambda t: t / per_realization))
            top.set_xlabel("cube time prorated to n, s")
        handles, labels = axes[0].get_legend_handles_labels()  # the target only: the colours are in axes[1]
        axes[0].legend([h for h, t in zip(handles, labels) if not t.startswith("lambda")],
                       [t for t in labels if not t.startswith("lambda")], fontsize=7, loc="lower left")
        axes[1].legend(fontsize=6, ncol=2)
        save(fig, "Adaptive ensemble: prefixes of every (xi, lambda) cell against the fast rule's half-width",
             "frontier_prefix.png")
    return paths
