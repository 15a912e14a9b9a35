"""The atlas surrogate's provenance matches the code and configuration that fitted it: on a freshly
fitted small atlas, and on the one shipped in the package (once it is of the current format)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from g2tom.atlas import run as atlas
from g2tom.before_work.domains import resolve
from g2tom.atlas.fit import FORMAT_VERSION, code_hash, write_atlas_surrogate
from g2tom.before_work import load_scenario
from g2tom.predict.atlas import shipped_path
from g2tom.store import git_commit
from tests.test_atlas import BASE, DESIGN


def test_a_fitted_surrogate_records_the_code_and_configuration_that_made_it(tmp_path, small_atlas) -> None:
    base = load_scenario("paper_gt", BASE)  # the small atlas's (conftest's small_atlas: run_atlas(base, DESIGN))
    (tmp_path / "atlas").mkdir()
    _, doc = write_atlas_surrogate(shutil.copy(small_atlas, tmp_path / "atlas" / atlas.ATLAS_FILE))
    prov = doc["provenance"]
    assert doc["format_version"] == FORMAT_VERSION
    assert prov["code_hash"] == code_hash() and prov["g2tom_commit"] == git_commit()
    assert prov["config_hash"] == base.config_hash("fits")
    assert len(prov["atlas_config_hashes"].split()) == 5  # one per scene


def test_the_shipped_surrogate_matches_the_code_that_fitted_it() -> None:
    path = shipped_path()
    if path is None:
        pytest.skip("this installation ships no atlas surrogate")
    doc = json.loads(path.read_text())
    if int(doc.get("format_version", 1)) < FORMAT_VERSION:
        pytest.skip(f"the shipped atlas surrogate is of format {doc.get('format_version', 1)} (made at "
                    f"{doc['provenance'].get('g2tom_commit', '?')[:12]}, before issue 31): `make atlas` regenerates it")
    prov = doc["provenance"]
    assert prov["code_hash"] == code_hash(), "the fitting code changed since the shipped surrogate was fitted: make atlas"
    # `g2tom atlas` runs on the scenario as the command line resolves it (auto domains filled in)
    assert prov["config_hash"] == resolve(load_scenario("atlas")).config_hash("fits"), "atlas.toml (or its base) changed"
    commit = prov["g2tom_commit"].removesuffix("-dirty")
    root = Path(__file__).resolve().parents[1]
    # an ancestor of HEAD, not merely an object in the store: a local clone copies unreachable objects too
    # (an amended commit's), a clone over the network does not
    known = subprocess.run(["git", "-C", str(root), "merge-base", "--is-ancestor", commit, "HEAD"], capture_output=True)
    if (root / ".git").exists():
        assert known.returncode == 0, f"the shipped surrogate's commit {commit} is not in this branch's history"
