"""Where the full-field reference computes (``cpu`` or ``gpu``) and with which solver (``tamaas`` or ``g2tom``).

``tamaas`` is tamaas' operator and solver, the reference itself, on the CPU. ``g2tom`` is g2tom's
own operator and Polonsky-Keer solver (:mod:`g2tom.reference.fft_surface`,
:mod:`g2tom.reference.polonsky_keer`) written against an array namespace: NumPy on the CPU
(tested against tamaas), CuPy on a GPU (tested against both). Device ``auto`` is ``gpu`` when
CuPy imports and sees a device, else ``cpu``. The solver defaults to g2tom's on either: on the
CPU it gives tamaas' cases within 1.3e-7 (634 of the default GW set's 635; the other differs by
its one-pixel probe contact) in half the time, which buys the default set its eight surfaces
within the validation's budget; ``--solver tamaas`` runs the reference itself.
"""

from __future__ import annotations

from types import ModuleType

from g2tom.errors import install_hint

__all__ = ["DEVICES", "SOLVERS", "GPU_HINT", "gpu_missing", "resolve", "solver_for", "namespace"]

#: ``--device`` values.
DEVICES = ("cpu", "gpu", "auto")
#: ``--solver`` values.
SOLVERS = ("tamaas", "g2tom")
#: The command that installs CuPy (the optional extra ``gpu``: CuPy's wheel for CUDA 12).
GPU_HINT = install_hint("gpu", "cupy-cuda12x")


def gpu_missing() -> str | None:
    """Why the GPU cannot be used (CuPy missing, or no device it can see), or None when it can."""
    try:
        import cupy
    except ImportError as exc:
        return f"the GPU path needs CuPy, which is not installed ({exc}): install it with {GPU_HINT}"
    try:
        count = cupy.cuda.runtime.getDeviceCount()
    except Exception as exc:  # CuPy raises its own CUDARuntimeError without a driver  # noqa: BLE001
        return f"CuPy sees no GPU ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
    return None if count > 0 else "CuPy sees no GPU (0 devices)"


def resolve(device: str) -> str:
    """``cpu`` or ``gpu`` for a ``--device`` value (``auto``: ``gpu`` where :func:`gpu_missing` is None).

    Raises
    ------
    ValueError
        On a value outside :data:`DEVICES`, or ``gpu`` where the GPU cannot be used (the reason).
    """
    if device not in DEVICES:
        raise ValueError(f"--device {device!r} is not allowed: must be one of {', '.join(DEVICES)}")
    if device == "cpu":
        return "cpu"
    why = gpu_missing()
    if why is None:
        return "gpu"
    if device == "auto":
        return "cpu"
    raise ValueError(f"--device gpu cannot be used: {why}")


def solver_for(solver: str | None, device: str) -> str:
    """The solver for a ``--solver`` value (None: g2tom's) on a resolved device.

    Raises
    ------
    ValueError
        On a value outside :data:`SOLVERS`, or tamaas on the GPU.
    """
    if solver is None:
        return "g2tom"
    if solver not in SOLVERS:
        raise ValueError(f"--solver {solver!r} is not allowed: must be one of {', '.join(SOLVERS)}")
    if solver == "tamaas" and device == "gpu":
        raise ValueError("--solver tamaas is not allowed with --device gpu: tamaas runs on the CPU; "
                         "g2tom's solver runs on either")
    return solver


def namespace(device: str) -> ModuleType:
    """The array module of a resolved device: NumPy for ``cpu``, CuPy for ``gpu``."""
    if device == "gpu":
        import cupy

        return cupy
    import numpy

    return numpy
