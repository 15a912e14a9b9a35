"""g2tom's own full-field solver on the CPU against tamaas: one contact load step and one punch, same inputs, same run.

Both on NumPy / tamaas on the threads the CLI allows (one), on the inputs of
:mod:`g2tom.bench.reference_step`: medians of :data:`REPEATS`, the ratios tamaas over ours and
our largest differences from tamaas. Where tamaas is missing the benchmark says so.
"""

from __future__ import annotations

import os
from typing import Any

from g2tom.bench.reference_step import LOAD, largest_differences, row
from g2tom.config import Scenario
from g2tom.reference import missing_extra

__all__ = ["SIZES", "REPEATS", "run"]

#: Grid sizes (pixels a side).
SIZES = (256, 512)
#: Timed repeats.
REPEATS = 3


def run(scenario: Scenario) -> dict[str, Any]:
    """Rows by grid size (``scenario`` names the study only)."""
    why = missing_extra()
    if why is not None:
        return {"skipped": why}
    rows = [row(n, ("cpu", "g2tom", "g2tom"), ("cpu", "tamaas", "tamaas"), REPEATS, REPEATS, warm=False)
            for n in SIZES]
    return {"threads": os.environ.get("OMP_NUM_THREADS", "unset"), "load_F_prime": LOAD, "rows": rows,
            "largest_difference": largest_differences(rows)}
