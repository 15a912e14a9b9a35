"""Loading a scenario: bundled or TOML file, a base, ``--set`` overrides, validation; input files' text.

:func:`read_scenario` checks every value against its declaration (:mod:`g2tom.config.validation`);
a bad value stops it with one :class:`~g2tom.config.declare.ConfigError` naming the parameter, its
value and the allowed range. The checks across parameters run before work
(:func:`g2tom.before_work.load_scenario`, the loader every command uses).
"""

from __future__ import annotations

import dataclasses
import tomllib
import warnings
from importlib import resources
from pathlib import Path
from typing import Any, Iterable, Mapping

from g2tom.config.declare import ConfigError, format_range, parameter_key
from g2tom.config.materials import pair_properties
from g2tom.config.scenario import SECTIONS, Scenario
from g2tom.config.validation import check_field, unknown

__all__ = ["read_input_text", "bundled_scenarios", "read_scenario", "USED_ONLY_WITH", "RENAMED",
           "parameter_table"]


def read_input_text(option: str, path: str | Path, encoding: str = "utf-8") -> str:
    """The text of an input file given by ``option``, or one ConfigError line naming both.

    Parameters
    ----------
    option
        How the user named the file (``--csv``, ``--surrogate``), for the message.
    path
        The file.
    encoding
        Its text encoding (``utf-8-sig`` also accepts a leading byte-order mark).

    Raises
    ------
    ConfigError
        If ``path`` is a directory, does not exist, cannot be read (permissions) or is not
        text in ``encoding``.
    """
    path = Path(path)
    where = f"{option} {str(path)!r}"
    if path.is_dir():
        raise ConfigError(f"{where} is a directory: give a file")
    if not path.exists():
        raise ConfigError(f"{where} does not exist")
    try:
        return path.read_text(encoding=encoding)
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{where} is not UTF-8 text (byte {exc.start}: {exc.object[exc.start:exc.start + 1]!r})") from None
    except OSError as exc:
        raise ConfigError(f"{where} is unreadable ({exc.strerror or exc}): check its permissions") from None


def _build(data: Mapping[str, Any], *, name: str, description: str) -> Scenario:
    """The scenario of ``data`` (``{section: {key: value}}``), every value and combination checked."""
    sections: dict[str, Any] = {}
    for key in data:
        if key not in SECTIONS:
            raise unknown(key)
    for section, cls in SECTIONS.items():
        table = data.get(section, {})
        if not isinstance(table, Mapping):
            raise ConfigError(f"{section} = {table!r} is not allowed: must be a [{section}] table of parameters")
        given = dict(table)
        by_key = {parameter_key(f): f for f in dataclasses.fields(cls)}
        for k in given:
            if k not in by_key:
                raise unknown(f"{section}.{k}")
        kwargs = {
            by_key[k].name: check_field(section, by_key[k], v) for k, v in given.items()
        }
        sections[section] = cls(**kwargs)
    return Scenario(name=name, description=description, **sections)


def bundled_scenarios() -> list[str]:
    """Names of the scenarios shipped with the package."""
    files = resources.files("g2tom.scenarios")
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def _parse_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # a bare word such as fixed_point


def _read_toml(config: str | Path) -> tuple[dict[str, Any], str]:
    text_name = str(config)
    if text_name in bundled_scenarios():
        text = resources.files("g2tom.scenarios").joinpath(f"{text_name}.toml").read_text()
        return tomllib.loads(text), text_name
    path = Path(config)
    if not path.is_file():
        raise ConfigError(
            f"--config {text_name!r} is neither a bundled scenario "
            f"({', '.join(bundled_scenarios())}) nor a TOML file"
        )
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"--config {text_name!r}: not valid TOML ({exc})") from None
    return _with_new_names(data), path.stem


def _with_base(data: dict[str, Any], seen: tuple[str, ...] = ()) -> tuple[dict[str, Any], str]:
    """A scenario's table merged over its ``base`` (a bundled scenario, which may have a base of its
    own), and the description of the nearest base that has one."""
    base = data.pop("base", None)
    if base is None:
        return data, ""
    if base not in bundled_scenarios():
        raise ConfigError(f"base = {base!r} is not a bundled scenario ({', '.join(bundled_scenarios())})")
    if base in seen:
        raise ConfigError(f"base = {base!r} is its own base ({' -> '.join(seen + (base,))})")
    merged, _ = _read_toml(base)
    merged.pop("name", None)
    own = str(merged.pop("description", ""))
    merged, further = _with_base(merged, seen + (base,))
    for section, values in data.items():
        if isinstance(values, dict) and isinstance(merged.get(section), dict):
            merged[section].update(values)
        else:
            merged[section] = values
    return merged, own or further


def read_scenario(
    config: str | Path = "paper", overrides: Iterable[str] | Mapping[str, Any] = ()
) -> Scenario:
    """Read a bundled scenario by name or a TOML file, apply overrides and check each value.

    The checks across parameters are not run here: :func:`g2tom.before_work.load_scenario` runs them
    on what this returns.

    Parameters
    ----------
    config
        A bundled scenario name (see :func:`bundled_scenarios`) or a path to a TOML file.
        A file may set ``base = "paper"`` to start from a bundled scenario (which may itself
        start from another: ``paper_gt`` from ``paper``, ``published`` from ``paper_gt``).
    overrides
        ``"section.key=value"`` strings (values in TOML syntax) or a mapping
        ``{"section.key": value}``.

    Raises
    ------
    ConfigError
        Naming the parameter, its value and the allowed range.
    """
    data, name = _read_toml(config)
    own = {f"{section}.{key}" for section, table in data.items() if isinstance(table, dict) for key in table}
    # the settings the user chose (a file's own, not those of its base or of a bundled scenario)
    explicit = set() if str(config) in bundled_scenarios() else set(own)
    name = str(data.pop("name", name))
    description = str(data.pop("description", ""))
    data, base_description = _with_base(data)
    description = description or base_description
    items = overrides.items() if isinstance(overrides, Mapping) else (
        _split_override(o) for o in overrides
    )
    overridden: set[str] = set()
    for dotted, value in items:
        dotted = RENAMED.get(dotted, dotted)
        section, _, key = dotted.partition(".")
        if section not in SECTIONS or not key:
            raise unknown(dotted)
        data.setdefault(section, {})[key] = value
        overridden.add(dotted)
    explicit |= overridden
    winners = overridden if BODIES in overridden else own | overridden
    return _settle(_with_bodies(_build(data, name=name, description=description), winners), explicit)


#: The parameter naming the bodies, and the parameters it fills: (E*, rho*, H) of
#: :func:`~g2tom.config.materials.pair_properties`, each unless one of its keys was given.
BODIES = "material.bodies"
_FILLED_BY_BODIES = (("modulus", ("material.modulus", "material.E", "material.nu")),
                     ("rho", ("material.rho",)),
                     ("hardness", ("material.hardness",)))


def _with_bodies(s: Scenario, given: set[str]) -> Scenario:
    """``s`` with the effective modulus, resistivity and hardness of its named bodies
    (``material.bodies``), each where none of its keys is in ``given`` (the settings made where the
    bodies were named, or later: a value given beside the names, or after them, wins)."""
    bodies = s.material.bodies
    if not bodies:
        return s
    if len(bodies) > 2:
        raise ConfigError(f"{BODIES} = {bodies!r} names {len(bodies)} bodies: must name one (both bodies) or two")
    values = dict(zip(("modulus", "rho", "hardness"), pair_properties(bodies)))
    filled = {name: values[name] for name, keys in _FILLED_BY_BODIES if not given.intersection(keys)}
    return dataclasses.replace(s, material=dataclasses.replace(s.material, **filled))


#: Parameters that moved, by their old key: the compute options that left the science sections.
RENAMED: dict[str, str] = {
    "cube.method": "compute.interaction_sum",
    "cube.chunk": "compute.cube_chunk",
    "oxide.chunk": "compute.oxide_chunk",
    "oxide.batch": "compute.oxide_batch",
}


def _with_new_names(data: dict[str, Any]) -> dict[str, Any]:
    """A scenario file's ``data`` with each old key of :data:`RENAMED` moved to its new key, with a
    warning naming both (an old key given with ``--set`` is moved as it is read)."""
    for old, new in RENAMED.items():
        section, _, key = old.partition(".")
        table = data.get(section)
        if isinstance(table, dict) and key in table:
            new_section, _, new_key = new.partition(".")
            warnings.warn(f"{old} is now {new} (a compute option, in no configuration hash): read as {new}; "
                          f"rename it in the scenario file", stacklevel=5)
            data.setdefault(new_section, {}).setdefault(new_key, table.pop(key))
    return data


#: Settings used only under another setting's value: key -> (that setting, its value, what is used instead).
USED_ONLY_WITH: dict[str, tuple[str, str, str]] = {
    "fits.min_force": ("fits.fit_range", "force", "fits.min_force_normalized"),
    "fits.min_force_normalized": ("fits.fit_range", "force_normalized", "fits.min_force"),
}


def _settle(s: Scenario, explicit: set[str]) -> Scenario:
    """Defaults that follow the grid, and a warning for each chosen setting that has no effect.

    ``surrogate.rank`` left at its default follows the oxide grid (at most
    min(len(oxide.xi), len(oxide.lambda))); one the user set is kept, and
    :func:`check_surrogate_grid` refuses it when out of range. A setting of
    :data:`USED_ONLY_WITH` the user set while another setting overrides it is warned about,
    naming that setting.

    Parameters
    ----------
    s
        The scenario as built.
    explicit
        ``section.key`` of every setting the user chose (``--set``, or the TOML file's own).
    """
    flat = s.flat()
    for key, (control, needed, instead) in USED_ONLY_WITH.items():
        if key in explicit and flat[control] != needed:
            warnings.warn(f"{key} = {flat[key]:g} has no effect: {control} = {flat[control]!r} selects by {instead} "
                          f"instead; set {control} = {needed!r} for {key} to count", stacklevel=3)
    top = min(len(s.oxide.xi), len(s.oxide.lambda_))
    if "surrogate.rank" not in explicit and s.surrogate.rank > top:
        s = dataclasses.replace(s, surrogate=dataclasses.replace(s.surrogate, rank=top))
    return s


def _split_override(text: str) -> tuple[str, Any]:
    if "=" not in text:
        raise ConfigError(f"--set {text!r}: expected key=value, e.g. roughness.sigma=2e-5")
    key, _, value = text.partition("=")
    return key.strip(), _parse_value(value.strip())


def parameter_table() -> list[tuple[str, Any, str, str, str]]:
    """Every parameter as ``(key, default, unit, allowed range, description)``."""
    rows = []
    for section, cls in SECTIONS.items():
        default = cls()
        for f in dataclasses.fields(cls):
            rows.append(
                (f"{section}.{parameter_key(f)}", getattr(default, f.name), f.metadata["unit"],
                 format_range(f.metadata), f.metadata["doc"])
            )
    return rows
