"""The metadata registry (g2tom.variables, pipeline/variables.toml): every written variable declared
once, with units and a long name, and the schema modules, the reductions and the predictor read from it."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any, Iterator

from g2tom.atlas.schema import ATLAS
from g2tom.bench.schema import FRONTIER, STABILITY
from g2tom.predict.queries import OUTPUT_COLUMNS
from g2tom.reference.variables import VARIABLES
from g2tom.stages.schema import COORDINATES, SCHEMA, SURROGATE_COORDINATES
from g2tom.variables import namespace, registry

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "tests" / "fixtures"
#: The modules whose variables' attributes come from the registry, and the four schema modules among them.
SCHEMA_MODULES = ("stages/schema.py", "reference/variables.py", "bench/schema.py", "atlas/schema.py")
READERS = SCHEMA_MODULES + ("reductions.py", "predict/predictor.py")
#: Namespaces whose entries take the shape of their inputs, so declare no dims.
SHAPELESS = {"predict"}


def namespaces(table: dict[str, Any] | None = None, path: str = "") -> Iterator[tuple[str, dict[str, Any]]]:
    """``(dotted path, table)`` of every namespace of variables in the registry (``texts`` left out)."""
    for key, value in (registry() if table is None else table).items():
        here = f"{path}.{key}" if path else key
        if here == "texts":
            continue
        entries = value.values()
        if all(isinstance(v, dict) and not {"units", "long_name", "dims"} & v.keys() for v in entries):
            yield from namespaces(value, here)
        else:
            yield here, value


def test_the_registry_is_the_shipped_file() -> None:
    """tomllib refuses a key declared twice in one table: each name appears once per namespace."""
    assert registry() == tomllib.loads((ROOT / "pipeline" / "variables.toml").read_text(encoding="utf-8"))
    assert {path for path, _ in namespaces()} == {
        "stages.coordinates", "stages.surrogate_coordinates", "stages.oxide", "stages.contact", "stages.cube",
        "stages.fits", "stages.surrogate", "validate", "bench.frontier", "bench.sweep", "bench.stability", "atlas",
        "predict", "chain", "reference.cases", "surface"}


def test_every_entry_has_units_and_a_long_name() -> None:
    missing = [f"{path}.{name}" for path, table in namespaces() for name, declared in table.items()
               if isinstance(declared, dict)
               and not (isinstance(declared.get("units"), str) and isinstance(declared.get("long_name"), str)
                        and declared["long_name"] and (path in SHAPELESS or isinstance(declared.get("dims"), list)))]
    assert not missing, f"entries without units, long_name or dims: {missing}"


def test_every_declaration_is_written_once() -> None:
    """A variable another namespace declares already is a reference to it, not a second copy."""
    seen: dict[tuple, str] = {}
    twice = []
    for path, table in namespaces():
        for name, declared in table.items():
            if isinstance(declared, str):
                continue
            key = (tuple(declared.get("dims", ())), declared["units"], declared["long_name"])
            if key in seen:
                twice.append(f"{path}.{name} = {seen[key]}")
            seen.setdefault(key, f"{path}.{name}")
    assert not twice, f"write these as references: {twice}"


def test_every_reference_names_a_declaration() -> None:
    references = {f"{path}.{name}": target for path, table in namespaces() for name, target in table.items()
                  if isinstance(target, str)}
    assert references, "the shared coordinates are referenced, not copied"
    for source, target in references.items():
        head, name = target.rsplit(".", 1)
        assert isinstance(dict(namespaces()).get(head, {}).get(name), dict), f"{source} -> {target}: not a declaration"


def test_the_schema_modules_hold_the_registry() -> None:
    assert SCHEMA == {stage: namespace(f"stages.{stage}") for stage in ("contact", "oxide", "cube", "fits", "surrogate")}
    assert COORDINATES == namespace("stages.coordinates")
    assert SURROGATE_COORDINATES == namespace("stages.surrogate_coordinates")
    assert VARIABLES == namespace("validate")
    assert (FRONTIER, STABILITY, ATLAS) == (namespace("bench.frontier"), namespace("bench.stability"), namespace("atlas"))


def test_predict_columns_are_the_registry() -> None:
    """g2tom.predict.queries.OUTPUT_COLUMNS (still its own list) says what the registry says."""
    assert OUTPUT_COLUMNS == {name: (v.units, v.long_name) for name, v in namespace("predict").items()}


def test_a_changed_entry_changes_what_is_written() -> None:
    """In a fresh interpreter whose registry has other units, the modules hand out those units."""
    script = """
import copy, g2tom.variables as v, numpy as np, xarray as xr
changed = copy.deepcopy(v.registry())
for path in ("stages.fits.geometric_mean", "stages.coordinates.xi", "validate.ratio", "bench.frontier.alpha",
             "bench.stability.seconds", "atlas.mu", "predict.resistance", "bench.sweep.column"):
    table = changed
    for part in path.split("."):
        table = table[part]
    table["units"] = "changed"
v.registry = lambda: changed
from g2tom.stages.schema import SCHEMA
from g2tom.reference.variables import VARIABLES
from g2tom.bench.schema import FRONTIER, STABILITY, sweep_column
from g2tom.atlas.schema import ATLAS
from g2tom.reductions import reduce_realizations
r = reduce_realizations(xr.DataArray(np.ones((1, 2)), dims=("delta", "realization")), 1.0)
print(SCHEMA["fits"]["geometric_mean"].units, SCHEMA["oxide"]["xi"].units, VARIABLES["xi"].units,
      VARIABLES["ratio"].units, FRONTIER["alpha"].units, STABILITY["seconds"].units, ATLAS["mu"].units,
      sweep_column("cube", "alpha").units, r["geometric_mean"].attrs["units"])
"""
    found = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout.split()
    assert found == ["changed"] * 9


def _literal_units(path: Path) -> list[str]:
    """Where ``path`` writes a unit as a literal: ``units=...`` or ``"units": ...`` with a string constant,
    or (in a schema module) any string constant that is one of the registry's units."""
    units = {v.units for p, _ in namespaces() for v in namespace(p).values()}
    schema_module = str(path.relative_to(ROOT / "pipeline")) in SCHEMA_MODULES
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.keyword) and node.arg == "units" and isinstance(node.value, ast.Constant):
            found.append(f"line {node.lineno}: units={node.value.value!r}")
        elif isinstance(node, ast.Dict):
            found += [f"line {k.lineno}: 'units': {v.value!r}" for k, v in zip(node.keys, node.values)
                      if isinstance(k, ast.Constant) and k.value == "units" and isinstance(v, ast.Constant)]
        elif schema_module and isinstance(node, ast.Constant) and node.value in units:
            found.append(f"line {node.lineno}: {node.value!r}")
    return found


def test_the_readers_hold_no_unit_literals() -> None:
    literal = {name: lines for name in READERS if (lines := _literal_units(ROOT / "pipeline" / name))}
    assert not literal, f"units written in the code, not read from the registry: {literal}"


def test_the_stored_schemas_are_in_the_registry() -> None:
    """Every variable of the stored schema fixtures, as stored, is declared in the registry."""
    stored = [(f"stages.{stage}", name, dims, units, long_name)
              for stage, name, dims, units, long_name in json.loads((FIXTURES / "schema.json").read_text())]
    stored += [(f"bench.{group}", name, dims, units, long_name)
               for group, name, dims, units, long_name in json.loads((FIXTURES / "bench_schema.json").read_text())]
    stored += [("atlas", *row) for row in json.loads((FIXTURES / "atlas_schema.json").read_text())]
    assert len(stored) > 200
    declared = {path: namespace(path) for path, *_ in stored}
    absent = [f"{path}.{name}" for path, name, *attrs in stored
              if (v := declared[path].get(name)) is None or [list(v.dims), v.units, v.long_name] != attrs]
    assert not absent, f"stored but declared otherwise: {absent}"
