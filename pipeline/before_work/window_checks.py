"""The checks of a scenario's spot window, radial domain and oxide band, once they are numbers.

:func:`check_domains` runs as a scenario with an explicit ``contact.window`` and
``contact.r_max`` is loaded (:func:`g2tom.before_work.scenario_checks.check_scenario`), and
again on the resolved scenario (:func:`g2tom.before_work.domains.resolve`): both before any
work. It takes a scenario whose two domains are numbers, resolved or not, so it counts the window's
cells itself (:func:`g2tom.config.odd_cells`). Like the other checks it imports no numpy at the
top (``import pipeline`` stays free of it).
"""

from __future__ import annotations

import math
import warnings

from g2tom.config import ConfigError, Scenario, odd_cells

__all__ = ["check_domains", "FIELD_BYTES_PER_ENTRY"]


def check_domains(s: Scenario) -> None:
    """Cross-checks of the spot window, the radial domain and the oxide band once both are numbers.

    Raises
    ------
    ConfigError
        Naming ``contact.window`` (or ``oxide.lambda``) when the window's corners leave the
        radial domain, the window holds fewer than 3 cells, or the band holds no mode.
    """
    window = s.contact.window * s.indenter.radius
    r_max = s.contact.r_max * s.indenter.radius
    n_cells = odd_cells(window, s.cell_size)
    corner = math.sqrt(2.0) * (n_cells - 1) / 2.0 * s.cell_size  # radius of the corner cell centres
    if corner > r_max:
        raise ConfigError(
            f"contact.window = {s.contact.window!r} is out of range: its corner cell centres lie at "
            f"r = {corner:.6g} m, beyond the radial domain r <= contact.r_max * R* = {r_max:.6g} m; "
            f"the window must be <= about sqrt(2) * contact.r_max = {math.sqrt(2) * s.contact.r_max:.4g} (R*)"
        )
    if n_cells < 3:
        raise ConfigError(
            f"contact.window = {s.contact.window!r} is out of range: the window holds fewer than "
            f"3 cells of pitch 1/sqrt(eta) = {s.cell_size:.3g} m"
        )
    _check_ensemble(s, n_cells)
    longest = max(s.oxide.lambda_) * s.cell_size
    if s.oxide.period == "window" and longest > window:
        n_modes = _modes_in_band(s, n_cells, max(s.oxide.lambda_))
        if n_modes == 0:
            raise ConfigError(
                f"oxide.lambda = {max(s.oxide.lambda_):g} is out of range: the window "
                f"({window:.3g} m) holds no Fourier mode of the band k1..ks; it must be "
                f"<= {window / s.cell_size:.3g} for this window"
            )
        warnings.warn(
            f"oxide.lambda = {max(s.oxide.lambda_):g}: the correlation length "
            f"({longest:.3g} m) exceeds the window ({window:.3g} m); the band holds only "
            f"{n_modes} independent Fourier modes",
            stacklevel=3,
        )


def _modes_in_band(s: Scenario, n_cells: int, lam: float) -> int:
    """Independent modes of ``lam``'s band on the lattice of the window of ``n_cells`` cells a side:
    the size of :func:`g2tom.physics.oxide_band.band`, 0 where it holds none."""
    from g2tom.physics import oxide_band  # here, not above: import pipeline stays free of numpy

    try:
        return oxide_band.band(n_cells, s.cell_size, lam, s.oxide.ks_ratio, s.oxide.hurst).size
    except ValueError:  # the band holds no lattice mode (every other argument is in range here)
        return 0


#: Bytes per realization and coefficient-table entry while fields are evaluated (complex table,
#: its partial DFT and workspace).
FIELD_BYTES_PER_ENTRY = 48


def _physical_memory() -> int:
    """Physical memory of the machine, in bytes (psutil: also on Windows, which has no os.sysconf).

    The bound of one chunk of fields, which no run can exceed; the plan's memory checks use the
    memory available now instead (:func:`g2tom.before_work.plan.available_memory`).
    """
    import psutil

    return int(psutil.virtual_memory().total)


def _check_ensemble(s: Scenario, n_cells: int) -> None:
    """Adaptive-ensemble limits and the memory a spectral resolution needs on a window of
    ``n_cells`` cells a side."""
    ox = s.oxide
    if ox.ensemble == "adaptive" and ox.max_realizations < ox.min_realizations:
        raise ConfigError(
            f"oxide.max_realizations = {ox.max_realizations} is out of range: must be >= "
            f"oxide.min_realizations = {ox.min_realizations} (the first batch)"
        )
    if ox.period != "spectral":
        return
    top = math.floor(ox.ks_ratio * max(ox.spectral_resolution, n_cells / (2.0 * min(ox.lambda_))))
    fields = max(s.compute.oxide_chunk, s.compute.cube_chunk)
    need = FIELD_BYTES_PER_ENTRY * fields * (top + 1) * (2 * top + 1)
    have = _physical_memory()
    per_field = need / fields
    defaults = type(s.compute)()
    if need > have and fields > max(defaults.oxide_chunk, defaults.cube_chunk) and per_field <= have:
        key = "compute.oxide_chunk" if s.compute.oxide_chunk >= s.compute.cube_chunk else "compute.cube_chunk"
        raise ConfigError(
            f"{key} = {fields} is out of range: a chunk of {fields} fields would need {need / 2**30:.3g} GiB, more "
            f"than the machine's {have / 2**30:.3g} GiB; it must be <= {int(have // per_field)}"
        )
    if need > have:
        raise ConfigError(
            f"oxide.spectral_resolution = {ox.spectral_resolution:g} is out of range: a chunk of "
            f"{fields} fields would need {need / 2**30:.3g} GiB, more than the machine's "
            f"{have / 2**30:.3g} GiB; lower it (the band's top index is {top})"
        )
