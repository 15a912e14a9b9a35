"""Report section "The measured-surface chain": the random-process surface's height map through
``g2tom roughness`` and ``g2tom predict`` against its full field (``chain.nc`` of
:mod:`g2tom.predict.chain`), the ratio per load."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.analysis.report_blocks import Block, table

__all__ = ["chain_blocks"]


def _cell(mean: float, se: float) -> str:
    if not np.isfinite(mean):
        return "-"
    return f"{mean:.3f}" + (f" ± {se:.3f}" if np.isfinite(se) else "")


def chain_blocks(data_dir: Path) -> list[Block]:
    """Section "The measured-surface chain": per load, chain / full field, clean and per oxide case, with
    the set's own parameters beside it."""
    from g2tom.predict.chain import CHAIN_FILE
    from g2tom.reference.validate import output_folder

    path = output_folder(Path(data_dir), "random_process") / CHAIN_FILE
    blocks = [Block("h3", "The measured-surface chain: height map -> roughness -> predict, against the full field")]
    if not path.is_file():
        return blocks + [Block("p", "Not available: run `g2tom validate --surface random_process`, then "
                                    "`python -m g2tom.predict.chain`.")]
    with xr.open_dataset(path, engine="netcdf4") as c:
        c = c.load()
    n = c.sizes["realization"]
    blocks.append(Block("p", (
        f"The validation's random-process surface, realizations {', '.join(str(int(r)) for r in c['realization'].values)}, "
        f"written as {int(c.attrs['map_pixels'])}^2 height maps of {float(c.attrs['map_pixel']) * 1e6:.3g} um pixels, "
        f"measured by `g2tom roughness` (sigma {np.mean(c['measured_sigma'].values) * 1e6:.4g} um, eta "
        f"{np.mean(c['measured_eta'].values):.4g} m^-2, beta {np.mean(c['measured_beta'].values) * 1e6:.4g} um against "
        f"the spectrum's {float(c.attrs['set_sigma']) * 1e6:.4g} um, {float(c.attrs['set_eta']):.4g} m^-2, "
        f"{float(c.attrs['set_beta']) * 1e6:.4g} um; mu {np.mean(c['measured_mu'].values):.3g}, Pi "
        f"{np.mean(c['measured_Pi'].values):.3g}) and predicted by `g2tom predict --roughness` ({c.attrs['answered_by']}) "
        f"at the forces the full field was solved at. Ratio predicted / full field, geometric mean over the {n} "
        f"realization(s) ± the standard error of its ln; 'known': the same prediction with the spectrum's own "
        f"sigma, eta, beta (the chain without the measurement).")))
    header = ["F'", "in the domain", "clean", "clean, known"]
    cases = [(x, lam) for x in c["xi"].values for lam in c["lambda"].values]
    header += [f"xi {x:g}, lambda {lam:g}" for x, lam in cases] + [f"xi {x:g}, lambda {lam:g}, known" for x, lam in cases]
    rows = []
    for k in range(c.sizes["load"]):
        row = [f"{float(c['force_normalized'].values[k]):.3g}",
               f"{int(c['inside_domain'].values[:, k].sum())} of {n}",
               _cell(float(c["ratio_clean_mean"].values[k]), float(c["ratio_clean_standard_error"].values[k])),
               _cell(float(c["ratio_clean_known_mean"].values[k]), float(c["ratio_clean_known_standard_error"].values[k]))]
        for name in ("ratio", "ratio_known"):
            for x, lam in cases:
                sel = {"xi": x, "lambda": lam}
                row.append(_cell(float(c[f"{name}_mean"].sel(sel).values[k]),
                                 float(c[f"{name}_standard_error"].sel(sel).values[k])))
        rows.append(row)
    blocks.append(table(header, rows))
    return blocks
