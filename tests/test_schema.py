"""The variable schemas (g2tom.stages.schema, g2tom.bench.schema) against their stored lists, and the
files against the schema."""

from __future__ import annotations

import json
from pathlib import Path

import xarray as xr

from g2tom.atlas.schema import ATLAS
from g2tom.bench.schema import FRONTIER, STABILITY
from g2tom.stages.schema import SCHEMA, matches

STORED = Path(__file__).parent / "fixtures" / "schema.json"
BENCH_STORED = Path(__file__).parent / "fixtures" / "bench_schema.json"
ATLAS_STORED = Path(__file__).parent / "fixtures" / "atlas_schema.json"


def test_schema_is_the_stored_list() -> None:
    """Every variable's dims, units and long name as stored: a change to a file's CF attributes is deliberate."""
    rows = [[stage, name, list(v.dims), v.units, v.long_name] for stage, vs in SCHEMA.items() for name, v in sorted(vs.items())]
    assert rows == json.loads(STORED.read_text())



def test_bench_schema_is_the_stored_list() -> None:
    """The benchmark files' variables as they were written before the schema (the sweep tables'
    columns are made per key by g2tom.bench.schema.sweep_column)."""
    declared = {"frontier": FRONTIER, "stability": STABILITY}
    rows = [[name, var, list(v.dims), v.units, v.long_name] for name, vs in declared.items() for var, v in sorted(vs.items())]
    assert rows == json.loads(BENCH_STORED.read_text())

def test_atlas_schema_is_the_stored_list() -> None:
    """The atlas files' own variables as they were written before their schema (g2tom.atlas.schema)."""
    rows = [[name, list(v.dims), v.units, v.long_name] for name, v in sorted(ATLAS.items())]
    assert rows == json.loads(ATLAS_STORED.read_text())


def written_against_schema(data_dir: Path) -> list[str]:
    """The variables of the stage files under ``data_dir`` that their schema lacks or labels otherwise."""
    wrong = []
    for stage, declared in SCHEMA.items():
        with xr.open_dataset(data_dir / f"{stage}.nc", decode_cf=False) as ds:
            for name, var in ds.variables.items():
                if "units" not in var.attrs:  # string labels
                    continue
                if name not in declared or not matches(stage, name, var.dims, var.attrs):
                    wrong.append(f"{stage}.nc: {name} {var.dims} {var.attrs.get('units')!r} {var.attrs.get('long_name')!r}")
    return wrong
