"""Figures of stage 1: the Greenwood–Tripp solution (paper Fig. 4) and its spots (Fig. 5: the
cell grid's spots, or on discrete asperities one surface of the pool's touching asperities).

The Hertz references exist for the sphere only: other indenters draw the Greenwood–Tripp
curves alone and say so. The spot maps are rasters (one pixel per cell), so they cost the
same for 57^2 or 10^6 cells.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from g2tom.analysis.style import LABELS, context, equals, save, size
from g2tom.config import Scenario
from g2tom.physics.asperity import area_fraction
from g2tom.physics.hertz import hertz_force
from g2tom.store import read_stage

__all__ = ["write", "FIG5_DELTAS", "FIG4_DELTA"]

#: delta / sigma of the four panels of Fig. 5 and of Fig. 4 (Table 1).
FIG5_DELTAS: tuple[float, ...] = (2.0, 0.0, -1.75, -3.0)
FIG4_DELTA = -2.0


def _nearest(ds: xr.Dataset, target: float) -> int:
    return int(np.argmin(np.abs(ds.delta_sigma.values - target)))


def _fig4(ds: xr.Dataset, scenario: Scenario, path: Path) -> Path:
    rough, e_star = scenario.roughness, scenario.material.E_star
    radius = scenario.indenter.radius
    k = _nearest(ds, FIG4_DELTA)
    one = ds.isel(delta=k)
    sigma = rough.sigma
    rn = ds.r.values / np.sqrt(radius * sigma)
    p_bar = e_star * np.sqrt(sigma / radius)  # pressure scale E* sqrt(sigma/R*), Pa
    sphere = scenario.indenter.shape == "sphere"
    extent = float(one.hertz_radius) if sphere else _contact_radius(one)
    keep = rn <= 3.5 * max(1.0, extent / np.sqrt(radius * sigma))
    fig, ax = plt.subplots(2, 3, figsize=size(2, 4.6), layout="constrained")
    title = f"{equals('delta_sigma', float(one.delta_sigma), '.2f')}, $F$ = {float(one.force):.0f} N"
    a = ax[0, 0]
    a.plot(rn[keep], one.pressure[keep] / p_bar, label="Greenwood–Tripp")
    if sphere:
        a.plot(rn[keep], one.hertz_pressure[keep] / p_bar, "--", label="Hertz, same force")
    a.set(xlabel=LABELS["radius_normalized"], ylabel=LABELS["pressure_normalized"], title="(a) pressure")
    a.legend()
    a = ax[0, 1]
    a.plot(rn[keep], (one.delta.values + one.profile[keep]) / sigma, "k--", label="initial (rigid)")
    a.plot(rn[keep], one.separation[keep] / sigma, label="Greenwood–Tripp")
    if sphere:
        a.plot(rn[keep], one.hertz_separation[keep] / sigma, ":", label="Hertz")
    a.axhline(0, color="0.6", lw=0.8)
    a.set(xlabel=LABELS["radius_normalized"], ylabel=LABELS["gap_normalized"], title="(b) gap above the mean plane")
    a.legend()
    a = ax[0, 2]
    a.plot(rn[keep], one.displacement[keep] / sigma, label="Greenwood–Tripp")
    if sphere:
        a.plot(rn[keep], one.hertz_displacement[keep] / sigma, "--", label="Hertz")
    a.set(xlabel=LABELS["radius_normalized"], ylabel=LABELS["displacement_normalized"], title="(c) displacement")
    a.legend()
    a = ax[1, 0]
    a.plot(rn[keep], one.area_fraction[keep], label=r"$A^*$")
    if sphere:
        a.axvline(float(one.hertz_radius) / np.sqrt(radius * sigma), color="C1", ls="--", label="Hertz radius")
    a.set(xlabel=LABELS["radius_normalized"], ylabel=LABELS["area_fraction"], title="(d) area fraction")
    a.legend()
    a = ax[1, 1]
    rigid = area_fraction(one.delta.values + one.profile.values, sigma, rough.eta, rough.beta)
    a.semilogy(rn, one.area_fraction, label=r"$A^*$")
    a.semilogy(rn, rigid, "--", label="Eq. 22 (rigid, with the 1/2)" if sphere else f"rigid {scenario.indenter.shape}")
    a.set_ylim(1e-30, 1.0)
    a.set(xlabel=LABELS["radius_normalized"], ylabel=LABELS["area_fraction"], title="(e) area fraction, semi-log")
    a.legend()
    a = ax[1, 2]
    d = ds.delta_sigma.values
    a.semilogy(d, ds.force, "o-", label="Greenwood–Tripp")
    if sphere:
        hertz = hertz_force(-ds.delta.values, radius, e_star)
        a.semilogy(d[hertz > 0], hertz[hertz > 0], "s--", label="Hertz, same interpenetration")
    a.invert_xaxis()
    a.set(xlabel=LABELS["delta_sigma"], ylabel=LABELS["force"], title="(f) force")
    a.legend(loc="upper left")  # the force rises to the right: the corner stays empty
    note = "" if sphere else f" — {scenario.indenter.shape}: Hertz and Eq. 22 apply to the sphere only, not drawn"
    fig.suptitle(f"Greenwood–Tripp contact ({scenario.name}): {title}{note}")
    return save(fig, path)


def _contact_radius(one: xr.Dataset) -> float:
    """Radius (m) inside which the pressure exceeds 1 % of its peak (the contact's extent)."""
    p = one.pressure.values
    inside = np.flatnonzero(p >= 0.01 * p.max()) if p.max() > 0 else np.array([0])
    return float(one.r.values[inside[-1]])


def _fig5_discrete(ds: xr.Dataset, scenario: Scenario, path: Path) -> Path:
    """Fig. 5 on discrete asperities: the first surface of the pool, each touching asperity a dot
    at its position, its area and grey level growing with its contact radius."""
    count = int(ds.spot_count.values[0])
    x_mm, y_mm = ds.asperity_x.values[0, :count] * 1e3, ds.asperity_y.values[0, :count] * 1e3
    radius = ds.asperity_radius.isel(surface=0).transpose("delta", "spot").values[:, :count] / scenario.cell_size
    top = float(radius.max()) if radius.size and radius.max() > 0 else 1.0
    reach = 1.1 * float(np.max(np.abs(np.concatenate([x_mm, y_mm])))) if count else 1.0
    fig, axes = plt.subplots(1, 4, figsize=size(2, 2.3), layout="constrained")
    for ax, target in zip(axes, FIG5_DELTAS):
        k = _nearest(ds, target)
        one = ds.isel(delta=k)
        on = radius[k] > 0
        image = ax.scatter(x_mm[on], y_mm[on], s=40.0 * (radius[k, on] / top) ** 2 + 1.0, c=radius[k, on],
                           cmap="Greys", vmin=0.0, vmax=top, edgecolors="0.3", linewidths=0.3)
        for value, colour, dashes, label in ((one.hertz_radius, "C3", "--", "Hertz"),
                                             (one.holm_radius, "C1", "-", "Holm–Greenwood (Greenwood–Tripp)")):
            if np.isfinite(value):
                ax.add_patch(plt.Circle((0, 0), 1e3 * float(value), fill=False, color=colour, ls=dashes, lw=1.2,
                                        label=label))
        ax.set(xlim=(-reach, reach), ylim=(-reach, reach), aspect="equal", xlabel=LABELS["x"],
               title=f"$F$ = {float(one.force):.0f} N, {int(on.sum())} spots")
    axes[0].set_ylabel(LABELS["y"])
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=2)
    fig.colorbar(image, ax=axes, shrink=0.8, label=LABELS["spot_radius"])
    fig.suptitle(f"Contact spots of one rough surface of the pool, dot size and grey level by radius ({scenario.name})")
    return save(fig, path)


def _fig5(ds: xr.Dataset, scenario: Scenario, path: Path) -> Path:
    if "asperity_radius" in ds:
        return _fig5_discrete(ds, scenario, path)
    x_mm = ds.x.values * 1e3
    half = 0.5 * (x_mm[1] - x_mm[0]) if x_mm.size > 1 else 0.5
    extent = (x_mm[0] - half, x_mm[-1] + half, x_mm[0] - half, x_mm[-1] + half)
    ratio_max = float(ds.spot_radius.max()) / scenario.cell_size
    fig, axes = plt.subplots(1, 4, figsize=size(2, 2.3), layout="constrained")
    for ax, target in zip(axes, FIG5_DELTAS):
        one = ds.isel(delta=_nearest(ds, target))
        image = ax.imshow(one.spot_radius.transpose("y", "x").values / scenario.cell_size, origin="lower",
                          extent=extent, cmap="Greys", vmin=0.0, vmax=ratio_max, interpolation="nearest")
        for value, colour, dashes, label in ((one.hertz_radius, "C3", "--", "Hertz"),
                                             (one.holm_radius, "C1", "-", "Holm–Greenwood")):
            if np.isfinite(value):
                ax.add_patch(plt.Circle((0, 0), 1e3 * float(value), fill=False, color=colour, ls=dashes, lw=1.2,
                                        label=label))
        ax.set(xlim=extent[:2], ylim=extent[2:], aspect="equal", xlabel=LABELS["x"],
               title=f"{equals('delta_sigma', float(one.delta_sigma), '.2f')}, $F$ = {float(one.force):.0f} N")
    axes[0].set_ylabel(LABELS["y"])
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=2)
    fig.colorbar(image, ax=axes, shrink=0.8, label=LABELS["spot_radius"])
    hertz = "" if scenario.indenter.shape == "sphere" else " (Hertz: sphere only)"
    fig.suptitle(f"Contact spots, one per cell of side $1/\\sqrt{{\\eta}}$, radius as grey level ({scenario.name}){hertz}")
    return save(fig, path)


def write(scenario: Scenario, data_dir: Path, out_dir: Path) -> list[Path]:
    """Write fig4_contact.png and fig5_spots.png from ``<data_dir>/contact.nc``."""
    ds = read_stage(data_dir, "contact", scenario)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with context():
        return [_fig4(ds, scenario, out_dir / "fig4_contact.png"), _fig5(ds, scenario, out_dir / "fig5_spots.png")]
