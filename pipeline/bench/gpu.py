"""The full-field reference on a GPU against the CPU: one contact load step and one punch, same inputs, same run.

The GPU is g2tom's own operator and solver on CuPy, the CPU tamaas (the reference, on the threads
the CLI allows it: one) (:mod:`g2tom.reference.devices`), on the inputs of
:mod:`g2tom.bench.reference_step` at several grid sizes: both up to 1024^2, the GPU alone
beyond (one CPU thread takes minutes a step there). The GPU's figures are medians of
:data:`REPEATS` after one untimed warm-up (cuFFT plans, kernel compilation), the CPU's of
:data:`REPEATS` below :data:`CPU_ONCE_FROM` pixels a side, else one solve. Where no GPU (or no
tamaas) is at hand the benchmark says so and measures nothing (or the GPU alone).
"""

from __future__ import annotations

import os
from typing import Any

from g2tom.bench.reference_step import LOAD, largest_differences, row
from g2tom.config import Scenario
from g2tom.reference import devices, missing_extra, scene

__all__ = ["BOTH", "GPU_ONLY", "REPEATS", "CPU_ONCE_FROM", "run"]

#: Grid sizes (pixels a side) solved on both devices.
BOTH = (256, 512, 1024)
#: Grid sizes solved on the GPU only.
GPU_ONLY = (2048, 4096)
#: Timed repeats.
REPEATS = 3
#: From this grid size the CPU solve is timed once.
CPU_ONCE_FROM = 1024


def _gpu_name() -> str:
    import cupy

    name = cupy.cuda.runtime.getDeviceProperties(0)["name"]
    return name.decode() if isinstance(name, bytes) else str(name)


def run(scenario: Scenario) -> dict[str, Any]:
    """GPU and CPU rows by grid size, or why nothing was measured (``scenario`` names the study only)."""
    why = devices.gpu_missing()
    if why is not None:
        return {"skipped": f"no GPU: {why}"}
    tamaas_missing = missing_extra()
    gpu, cpu = ("gpu", "g2tom", "gpu"), ("cpu", "tamaas", "cpu")
    rows = [row(n, gpu, cpu if tamaas_missing is None else None, REPEATS, REPEATS if n < CPU_ONCE_FROM else 1,
                warm=True) for n in BOTH]
    rows += [row(n, gpu, None, REPEATS, 0, warm=True) for n in GPU_ONLY]
    vset = scene.DEFAULT
    return {
        "gpu": _gpu_name(), "cpu_threads": os.environ.get("OMP_NUM_THREADS", "unset"),
        "window_m": vset.side / 2.0, "force_N": LOAD * vset.force_scale, "load_F_prime": LOAD,
        "cpu": "tamaas (skipped: " + tamaas_missing + ")" if tamaas_missing else "tamaas",
        "rows": rows, "largest_difference": largest_differences(rows),
    }
