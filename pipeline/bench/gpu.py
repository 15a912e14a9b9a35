"""The full-field reference on a GPU against the CPU: one contact load step and one punch, same inputs, same run.

The inputs are the validation's default scene (GW surface of realization 0 on the sphere, at the
load F' = 4.85 of its default set) on a window of half the set's side, at several grid sizes.
The CPU is tamaas (the reference, on the threads the CLI allows it: one), the GPU g2tom's own
operator and solver on CuPy (:mod:`pipeline.reference.devices`). Each GPU figure is a median of
:data:`REPEATS` after one untimed warm-up (cuFFT plans, kernel compilation); the CPU's is a
median of :data:`REPEATS` below :data:`CPU_ONCE_FROM` pixels a side, else one solve. Where no GPU
(or no tamaas) is at hand the benchmark says so and measures nothing.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from pipeline.bench.timing import median_time
from pipeline.config import Scenario
from pipeline.reference import devices, elastic, missing_extra, scene
from pipeline.reference.contact import contact_at_force
from pipeline.reference.punch import punch_conductance

__all__ = ["BOTH", "GPU_ONLY", "REPEATS", "CPU_ONCE_FROM", "LOAD", "run"]

#: Grid sizes (pixels a side) solved on both devices.
BOTH = (256, 512, 1024)
#: Grid sizes solved on the GPU only (one CPU thread takes minutes per step there).
GPU_ONLY = (2048, 4096)
#: Timed repeats.
REPEATS = 3
#: From this grid size the CPU solve is timed once.
CPU_ONCE_FROM = 1024
#: The load, F' (the quick set's heavier step, delta/sigma = -0.5 on the GW surface).
LOAD = 4.85


def _gpu_name() -> str:
    import cupy

    name = cupy.cuda.runtime.getDeviceProperties(0)["name"]
    return name.decode() if isinstance(name, bytes) else str(name)


def _timed(device: str, heights: np.ndarray, pixel: float, force: float, repeats: int,
           warm: bool) -> dict[str, Any]:
    """Median seconds of a contact step from rest (a fresh operator each time: solvers start from the
    operator's last solution) and of the punch on its contact set, and the answers."""
    vset = scene.DEFAULT
    n = heights.shape[0]

    def fresh() -> Any:
        return elastic.free_surface(n, pixel, vset.e_star, device)

    if warm:
        punch_conductance(fresh(), contact_at_force(fresh(), heights, force).contact, vset.rho)
    contact_seconds, state = median_time(lambda: contact_at_force(fresh(), heights, force), repeats)
    operator = fresh()
    punch_seconds, punch = median_time(lambda: punch_conductance(operator, state.contact, vset.rho), repeats)
    return {"contact_seconds": contact_seconds, "punch_seconds": punch_seconds, "state": state,
            "conductance": punch.conductance}


def _row(n: int, side: float, force: float, with_cpu: bool) -> dict[str, Any]:
    pixel = side / n
    heights = scene.rough_sphere(scene.DEFAULT, 0, n, side)
    on_gpu = _timed("gpu", heights, pixel, force, REPEATS, warm=True)
    row: dict[str, Any] = {"n": n, "pixel_m": pixel, "contact_pixels": int(on_gpu["state"].contact.sum()),
                           "gpu_contact_seconds": on_gpu["contact_seconds"],
                           "gpu_punch_seconds": on_gpu["punch_seconds"]}
    if not with_cpu:
        return row
    on_cpu = _timed("cpu", heights, pixel, force, REPEATS if n < CPU_ONCE_FROM else 1, warm=False)
    cpu_state, gpu_state = on_cpu["state"], on_gpu["state"]
    row.update({
        "cpu_contact_seconds": on_cpu["contact_seconds"], "cpu_punch_seconds": on_cpu["punch_seconds"],
        "contact_ratio": on_cpu["contact_seconds"] / on_gpu["contact_seconds"],
        "punch_ratio": on_cpu["punch_seconds"] / on_gpu["punch_seconds"],
        "force_difference": abs(gpu_state.force / cpu_state.force - 1.0),
        "delta_difference": abs(gpu_state.delta / cpu_state.delta - 1.0),
        "pressure_difference": float(np.abs(gpu_state.pressure - cpu_state.pressure).max() / cpu_state.pressure.max()),
        "contact_pixels_differing": int((gpu_state.contact != cpu_state.contact).sum()),
        "conductance_difference": abs(on_gpu["conductance"] / on_cpu["conductance"] - 1.0),
    })
    return row


def run(scenario: Scenario) -> dict[str, Any]:
    """GPU and CPU rows by grid size, or why nothing was measured (``scenario`` names the study only)."""
    why = devices.gpu_missing()
    if why is not None:
        return {"skipped": f"no GPU: {why}"}
    tamaas_missing = missing_extra()
    vset = scene.DEFAULT
    side, force = vset.side / 2.0, LOAD * vset.force_scale
    sizes = [(n, tamaas_missing is None) for n in BOTH] + [(n, False) for n in GPU_ONLY]
    rows = [_row(n, side, force, with_cpu) for n, with_cpu in sizes]
    compared = [r for r in rows if "contact_ratio" in r]
    largest = {key: max(r[key] for r in compared) for key in
               ("force_difference", "delta_difference", "pressure_difference", "conductance_difference",
                "contact_pixels_differing")} if compared else {}
    return {
        "gpu": _gpu_name(), "cpu_threads": os.environ.get("OMP_NUM_THREADS", "unset"),
        "window_m": side, "force_N": force, "load_F_prime": LOAD,
        "cpu": "tamaas (skipped: " + tamaas_missing + ")" if tamaas_missing else "tamaas",
        "rows": rows, "largest_difference": largest,
    }
