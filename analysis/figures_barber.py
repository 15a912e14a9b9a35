"""Barber's check of every spot discretization: kappa / kappa_Barber against F.

Reads ``<data_dir>/bench/spots.json`` (``g2tom bench --only spots``, part of ``make run``) and
draws, for mean_area, expected and asperities spots of Greenwood-Tripp's contact (whatever the
scenario's contact model), the clean conductance of Greenwood's form,
the point model and the point model with the lattice term over Barber's K / (E* rho*). Writes
nothing when the benchmark has not run.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from g2tom.analysis.style import LABELS, context, plain_log_ticks, save, size
from g2tom.config import Scenario

__all__ = ["write"]

STYLES = {"greenwood": "-", "point": "--", "point_lattice": ":"}
COLOURS = {"mean_area": "C0", "expected": "C2", "asperities": "C3"}


def write(scenario: Scenario, data_dir: Path, out_dir: Path) -> list[Path]:
    """``barber_spots.png`` from the spots benchmark, or nothing without it."""
    path = Path(data_dir) / "bench" / "spots.json"
    if not path.is_file():
        return []
    result = json.loads(path.read_text())
    with context():
        return [_draw(result, out_dir / "barber_spots.png")]


def _draw(result: dict, target: Path) -> Path:
    """Both panels (all ratios, and near 1) from the benchmark's ``result``, saved to ``target``."""
    fig, (full, near) = plt.subplots(1, 2, figsize=size(2, 2.9), layout="constrained")
    for spots, colour in COLOURS.items():
        entry = result[spots]
        for model, ratio in entry["barber_ratio"].items():
            values = np.asarray(ratio, float)
            if not np.isfinite(values).any():
                continue
            for ax in (full, near):
                ax.plot(entry["force_N"], values, STYLES[model], color=colour, marker=".",
                        label=f"{spots.replace('_', ' ')}, {model.replace('_', ' + ')}")
    for ax in (full, near):
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel(LABELS["force"])
    full.set_yscale("log")
    plain_log_ticks(full.yaxis)
    full.set_ylabel(LABELS["kappa_barber"])
    full.set_title("clean, every discretization")
    near.set_ylim(0.9, 1.1)
    near.set_title("near 1 (expected and asperities)")
    fig.legend(*full.get_legend_handles_labels(), loc="outside right center")
    return save(fig, target)
