"""Compute options (``[compute]``: the interaction-sum algorithm, chunk sizes, the adaptive batch) are
apart from the science: in no configuration hash, so changing one re-runs no stage; their old keys
(``cube.method``, ``cube.chunk``, ``oxide.chunk``, ``oxide.batch``) are read under the new ones."""

from __future__ import annotations

import dataclasses
import os

import pytest

from g2tom.before_work import load_scenario
from g2tom.cli.main import main
from g2tom.config import RENAMED, SECTIONS, STAGE_INPUTS, ConfigError
from g2tom.config.study_sections import Compute

#: A value other than the default, in range, for each compute option.
OTHER = {"interaction_sum": "direct", "cube_chunk": 7, "oxide_chunk": 3, "oxide_batch": 11}


def test_every_compute_option_has_another_value_here() -> None:
    assert set(OTHER) == {f.name for f in dataclasses.fields(Compute)}
    assert SECTIONS["compute"] is Compute


@pytest.mark.parametrize("name", sorted(OTHER))
def test_no_configuration_hash_holds_a_compute_option(name: str) -> None:
    base = load_scenario("paper")
    other = dataclasses.replace(base, compute=dataclasses.replace(base.compute, **{name: OTHER[name]}))
    assert other.compute != base.compute
    for stage in (*STAGE_INPUTS, None):
        assert other.config_hash(stage) == base.config_hash(stage), stage
    for stage in STAGE_INPUTS:
        assert not [k for k in other.stage_parameters(stage) if k.startswith("compute.")]


def test_a_science_setting_still_changes_its_hash() -> None:
    base = load_scenario("paper")
    other = load_scenario("paper", {"cube.crop_tolerance": 1e-4})
    assert other.config_hash("cube") != base.config_hash("cube")
    assert other.config_hash("oxide") == base.config_hash("oxide")


def test_changing_a_compute_option_rewrites_no_stamp(tmp_path) -> None:
    """``g2tom stamp`` (what make runs before every stage) leaves each stamp as it was: make says up to date."""
    args = ["stamp", "--config", "paper", "--data-dir", str(tmp_path)]
    assert main(args) in (0, None)
    stamps = sorted((tmp_path / ".stamps").glob("*.json"))
    assert [p.stem for p in stamps] == sorted(STAGE_INPUTS)
    before = {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in stamps}
    for name, value in OTHER.items():
        assert main([*args, "--set", f"compute.{name}={value!r}" if isinstance(value, str) else
                     f"compute.{name}={value}"]) in (0, None)
    assert {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in stamps} == before
    assert main([*args, "--set", "cube.crop_tolerance=1e-4"]) in (0, None)
    assert (tmp_path / ".stamps" / "cube.json").read_bytes() != before["cube.json"][0]


def test_old_keys_in_a_file_are_read_under_the_new_ones_with_a_warning(tmp_path) -> None:
    path = tmp_path / "old.toml"
    path.write_text('base = "paper"\n[cube]\nmethod = "direct"\nchunk = 7\n[oxide]\nchunk = 3\nbatch = 11\n')
    with pytest.warns(UserWarning) as caught:
        scenario = load_scenario(path)
    assert scenario.compute == Compute(**OTHER)
    said = " ".join(str(w.message) for w in caught)
    for old, new in RENAMED.items():
        assert f"{old} is now {new}" in said


def test_old_keys_on_the_command_line_are_read_under_the_new_ones() -> None:
    scenario = load_scenario("paper", ["cube.method=direct", "cube.chunk=7", "oxide.chunk=3", "oxide.batch=11"])
    assert scenario.compute == Compute(**OTHER)


def test_a_bad_compute_value_names_the_new_key() -> None:
    with pytest.raises(ConfigError, match="compute.cube_chunk = 0"):
        load_scenario("paper", ["cube.chunk=0"])
