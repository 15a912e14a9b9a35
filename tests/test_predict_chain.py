"""The measured-surface chain: the random-process surface's height map -> roughness -> predict,
against its full field (pipeline/predict/chain.py), on the quick validation set."""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
import pytest
import xarray as xr

from g2tom.atlas import run as atlas
from g2tom.atlas.fit import write_atlas_surrogate
from g2tom.predict import chain


@pytest.fixture(scope="module")
def validated(tmp_path_factory):
    pytest.importorskip("tamaas")
    from g2tom.reference.validate import chosen_set, output_folder, run_validation

    data = tmp_path_factory.mktemp("chain")
    out = output_folder(data, "random_process")
    # g2tom's side on one discretization: the chain reads the full field's resistances and the set, not
    # g2tom's answers of the other discretizations (the costliest part of this run)
    vset = dataclasses.replace(chosen_set(True, "random_process"), discretizations=("expected",))
    run_validation(vset, out, progress=False)
    return data


@pytest.fixture(scope="module")
def surrogate(tmp_path_factory, small_discrete_atlas):
    """The surrogate of conftest's small atlas on discrete asperities (mu 2 .. 8, Pi 10 .. 40; a small
    fixed pool of 8 surfaces), fitted on a copy of it."""
    folder = tmp_path_factory.mktemp("atlas") / "atlas"
    folder.mkdir()
    target, _ = write_atlas_surrogate(shutil.copy(small_discrete_atlas, folder / atlas.ATLAS_FILE))
    return target


def test_chain_measures_predicts_and_compares(validated, surrogate, capsys) -> None:
    assert chain.main(["--data-dir", str(validated), "--surrogate", str(surrogate)]) == 0
    from g2tom.reference.validate import output_folder

    with xr.open_dataset(output_folder(validated, "random_process") / chain.CHAIN_FILE) as c:
        c = c.load()
    # the height map measured: the summits' parameters within 10 % of the spectrum's closed form
    for name in ("sigma", "eta", "beta"):
        assert c[f"measured_{name}"].values == pytest.approx(c.attrs[f"set_{name}"], rel=0.10), name
    # the ratio is the prediction over the full field's resistance, per load
    with xr.open_dataset(output_folder(validated, "random_process") / "validate.nc") as v:
        ref = v["resistance_reference_clean"].values
    np.testing.assert_allclose(c["ratio_clean"].values, c["resistance_chain_clean"].values / ref, rtol=1e-12)
    assert np.all(np.isfinite(c["ratio_clean"].values)) and np.all(np.isfinite(c["ratio"].values))
    assert np.all(c["inside_domain"].values == 1)  # mu 3.46, Pi 18: inside (2..8, 10..40)
    # measured and known parameters give nearly the same answer: the measurement costs little here
    np.testing.assert_allclose(c["ratio_clean"].values, c["ratio_clean_known"].values, rtol=0.15)
    for name, var in c.variables.items():
        assert var.attrs.get("units") is not None and var.attrs.get("long_name"), name
    from g2tom.analysis.report_chain import chain_blocks

    blocks = chain_blocks(validated)
    assert blocks[-1].kind == "table" and len(blocks[-1].rows) == 1 + c.sizes["load"]


def test_chain_without_a_validation_is_refused_in_one_line(tmp_path, capsys) -> None:
    assert chain.main(["--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("g2tom: error: validate.nc") and "random_process" in err[0]
    assert not any(tmp_path.iterdir())
