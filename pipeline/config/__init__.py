"""Scenarios: the parameter set of a run, declared, loaded from TOML, overridden and validated.

A scenario is a nested, frozen set of dataclasses, one per section (``material``,
``roughness``, ...). Every field declares its unit, meaning and allowed range in its
metadata, so validation, documentation and provenance all come from one place. All values
are SI unless a field's unit says otherwise (``loading.delta_max`` is in units of sigma).

Bundled scenarios (``paper``, ``published``) live in :mod:`g2tom.scenarios` and are
chosen by name; any other value of ``--config`` is read as a TOML file path.

The package, top down: ``declare`` (how a parameter is declared; :data:`AUTO`,
:class:`ConfigError`), ``scene_sections`` and ``study_sections`` (the sections' parameters),
``scenario`` (:class:`Scenario`, its derived values and config hashes; :class:`ResolvedScenario`,
its domains resolved; :func:`odd_cells`), ``validation`` (each value against its declaration) and
``loading`` (:func:`read_scenario`). Config imports nothing else from the package; the checks
across parameters live before work, where :func:`g2tom.before_work.load_scenario` runs them on
every scenario it reads.
"""

from g2tom.config.declare import AUTO, ConfigError, format_range, parameter_key
from g2tom.config.loading import (
    RENAMED, USED_ONLY_WITH, bundled_scenarios, parameter_table, read_input_text, read_scenario)
from g2tom.config.scenario import (
    COMPUTE_SECTION, SECTIONS, STAGE_EXCLUDED, STAGE_INPUTS, STAGE_UPSTREAM, ResolvedScenario, Scenario, odd_cells)
from g2tom.config.scene_sections import (
    MAX_POOL_SURFACES, POOL_CONFIDENCE, Contact, Indenter, Loading, Material, Roughness)
from g2tom.config.study_sections import CHUNK_BYTES, KERNEL_CACHE_BYTES, Atlas, Compute, Cube, Fits, Oxide, Surrogate

__all__ = [
    "AUTO",
    "ConfigError",
    "read_input_text",
    "Scenario",
    "ResolvedScenario",
    "odd_cells",
    "read_scenario",
    "bundled_scenarios",
    "parameter_table",
    "parameter_key",
    "format_range",
    "USED_ONLY_WITH",
    "RENAMED",
    "SECTIONS",
    "COMPUTE_SECTION",
    "STAGE_INPUTS",
    "STAGE_EXCLUDED",
    "STAGE_UPSTREAM",
    "Material",
    "Roughness",
    "Indenter",
    "Loading",
    "Contact",
    "Oxide",
    "Cube",
    "Fits",
    "Surrogate",
    "Atlas",
    "Compute",
    "CHUNK_BYTES",
    "KERNEL_CACHE_BYTES",
    "MAX_POOL_SURFACES",
    "POOL_CONFIDENCE",
]
